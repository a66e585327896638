"""``gyrolab bridge``: a real gyro's output into a session position through the REST API.

bytes (``sources``: serial port, file, stdin; or ``recording``: a replayed raw capture)
→ frames (``lines``: text and KVH DSP-3000 lines; ``frames``: fixed binary frames, the
KVH DSP-1750 and any frame described by ``frame:SPEC``; set up by ``instruments``)
→ samples in °/h timed by the gyro's own counter (``samples``) → the server (``upload``),
all driven by ``run``.  Pure Python apart from the upload; no web imports.
"""
