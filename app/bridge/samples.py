"""Decoded frames → the samples GyroLab stores: rates in °/h, timed by the gyro's own
counter and output rate.

* a rate in deg/h, deg/s or rad/s: converted (1 °/s = 3600 °/h, 1 rad/s = 3600·180/π °/h);
* an angle increment Δθ per frame (KVH "delta angle", DSP-3000 "incremental angle"):
  ω = Δθ · f over the frame's own period 1/f (KVH manual: delta angle is the rate
  integrated over the time since the last output);
* an integrated angle θ (DSP-3000 "integrated angle"): ω = (θₖ − θⱼ) · f / (k − j)
  between consecutive kept frames j < k, so one sample fewer than frames.

The time of frame k is ``start_s + k / f``: the counter places it, the PC clock only
anchors the run's first frame (so positions recorded in separate runs share one clock).
A gap in k (frames lost or dropped) is counted, and shows in the times that are sent.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from app.bridge.frames import ANGLE_UNITS, RATE_UNITS, Frame
from app.core.exceptions import UserError
from app.core.units import SECONDS_PER_HOUR, TO_DEG_PER_HOUR

DEGREES_PER_ANGLE_UNIT = {"deg": 1.0, "rad": math.degrees(1.0), "arcsec": 1.0 / 3600.0}
UNITS = RATE_UNITS + ANGLE_UNITS


@dataclass(slots=True)
class Sample:
    time_s: float | None
    rate_deg_h: float
    temperature_c: float | None


class SampleMaker:
    """Turns frames into samples; counts the gaps between the samples it makes."""

    def __init__(
        self,
        unit: str,
        rate_hz: float | None,
        *,
        integrated: bool = False,
        start_s: float = 0.0,
    ) -> None:
        if unit not in UNITS:
            raise UserError("bridge.unit", unit=unit, known=", ".join(UNITS))
        is_angle = unit in ANGLE_UNITS
        if (is_angle or integrated) and not rate_hz:
            raise UserError("bridge.needs_rate")
        if integrated and not is_angle:
            raise UserError("bridge.integrated_unit")
        self.rate_hz = rate_hz
        self.integrated = integrated
        self.start_s = start_s
        if is_angle:
            self._factor = DEGREES_PER_ANGLE_UNIT[unit] * SECONDS_PER_HOUR * (rate_hz or 0.0)
        else:
            self._factor = TO_DEG_PER_HOUR[unit]
        self._last: Frame | None = None
        self.gaps = 0  # places where samples are missing between two that were kept
        self.absent = 0  # samples missing there in all

    def make(self, frames: list[Frame]) -> list[Sample]:
        samples = []
        rate_hz, start_s = self.rate_hz, self.start_s
        for frame in frames:
            last = self._last
            self._last = frame
            step = frame.count - last.count if last is not None else 1
            if step > 1:
                self.gaps += 1
                self.absent += step - 1
            if self.integrated:
                if last is None:
                    continue
                value = (frame.value - last.value) / step * self._factor
            else:
                value = frame.value * self._factor
            time_s = start_s + frame.count / rate_hz if rate_hz else None
            samples.append(Sample(time_s, value, frame.temperature_c))
        return samples
