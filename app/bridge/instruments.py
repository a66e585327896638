"""The instruments the bridge speaks: ``text``, ``kvh-dsp3000``, ``kvh-dsp1750`` and
``frame:SPEC``, each with its defaults (unit, output rate), set up as a decoder.

KVH DSP-1750/1760 (and the 1725/1775 IMUs), message format A (KVH technical manual,
"Normal Operating Mode Message Format A"): 36 bytes — header 0xFE81FF55; rotation about
X, Y, Z then acceleration X, Y, Z as big-endian IEEE-754 float32 (rotation: Δangle or
rate, radians or degrees, as configured; default Δangle in radians); a status byte (bits
0–2 gyro X/Y/Z valid, 4–6 accelerometers, 3 and 7 always 0); a counter 0–127; the
temperature as a big-endian int16 (°C, or 0.01 °C with ``=TEMPUNITS,C_100``); CRC-32/MPEG-2
over bytes 0–31, big-endian.  Default output rate 1000 Hz.

KVH DSP-3000 (RS-232, 38400 baud 8N1): a line ``(-)xxx.xxxxxx y`` per output period at
100 Hz, the reading as a rate (°/s), an incremental angle (°) or an integrated angle (°)
as configured, and y = 1 valid, 0 fault.

VectorNav VN-100/VN-200 (115200 baud): an ASCII sentence per output period at 40 Hz as
shipped (``$VNYMR``, ``$VNQMR`` or ``$VNIMU``, the angular rates in rad/s, an 8-bit
checksum or a 16-bit CRC; VectorNav UM001, asynchronous outputs), read by
:mod:`app.core.sentence_records`; the axis z unless ``--axis`` chooses another.
"""

from __future__ import annotations

import dataclasses
import re
from dataclasses import dataclass

from app.bridge.frames import FrameDecoder, FrameSpec, build_spec, parse_spec
from app.bridge.lines import Dsp3000Decoder, LineParser, SentenceDecoder, TextDecoder
from app.core.exceptions import UserError

FORMATS = ("text", "kvh-dsp3000", "kvh-dsp1750", "vectornav", "frame:SPEC")

KVH_DSP1750 = dataclasses.replace(
    build_spec(
        "FE 81 FF 55",
        [
            "x:>f4",
            "y:>f4",
            "z:>f4",
            "_:4",  # acceleration X, Y, Z (g)
            "_:4",
            "_:4",
            "status:u1!0x88",  # bits 3 and 7 are always 0
            "seq:u1%128",
            "temp:>i2",
        ],
        checksum="crc32-mpeg2",
        rate_hz=1000.0,
        unit="rad",
    ),
    axis_status_bits={"x": 0x01, "y": 0x02, "z": 0x04},
)
DSP3000_RATE_HZ = 100.0
DSP3000_BAUD = 38400
DSP1750_BAUD = 921600
VECTORNAV_RATE_HZ = 40.0  # the VN-100's asynchronous output rate as it leaves the factory
VECTORNAV_BAUD = 115200


@dataclass
class Instrument:
    """What the gyro sends and how to read it (the bridge's ``--format`` and friends)."""

    format: str = "text"
    axis: str | None = None
    unit: str | None = None  # default: the format's own
    rate_hz: float | None = None  # default: the format's own
    integrated: bool = False
    temperature_scale: float | None = None  # °C per count of the temperature field
    regex: re.Pattern | None = None  # text
    column: int | None = None  # text
    scale: float = 1.0  # text

    def spec(self) -> FrameSpec | None:
        if self.format == "kvh-dsp1750":
            return KVH_DSP1750
        if self.format.startswith("frame:"):
            return parse_spec(self.format.removeprefix("frame:"))
        return None

    def default_baud(self) -> int:
        bauds = {"kvh-dsp3000": DSP3000_BAUD, "kvh-dsp1750": DSP1750_BAUD}
        return {**bauds, "vectornav": VECTORNAV_BAUD}.get(self.format, 9600)


@dataclass
class Setup:
    """A decoder with the unit and output rate its frames are in."""

    decoder: TextDecoder | Dsp3000Decoder | SentenceDecoder | FrameDecoder
    unit: str
    rate_hz: float | None
    has_temperature: bool


def set_up(instrument: Instrument, *, mid_line: bool = True) -> Setup:
    """The decoder for ``instrument``; ``mid_line``: the stream may begin mid-line (a
    serial port) rather than at a line's start (a file)."""
    name = instrument.format
    if name == "text":
        if instrument.axis is not None:
            raise UserError("bridge.axis_needs_frames")
        parser = LineParser(instrument.regex, instrument.column, instrument.scale)
        decoder = TextDecoder(parser, mid_line=mid_line)
        return Setup(decoder, instrument.unit or "deg/h", instrument.rate_hz, False)
    if name == "kvh-dsp3000":
        if instrument.axis is not None:
            raise UserError("bridge.axis_needs_frames")
        decoder = Dsp3000Decoder(mid_line=mid_line)
        rate = instrument.rate_hz or DSP3000_RATE_HZ
        return Setup(decoder, instrument.unit or "deg/s", rate, False)
    if name == "vectornav":  # the axis the gyro's sensitive one: z unless chosen
        decoder = SentenceDecoder(instrument.axis or "z", mid_line=mid_line)
        rate = instrument.rate_hz or VECTORNAV_RATE_HZ
        return Setup(decoder, instrument.unit or "rad/s", rate, False)  # $VNIMU: per frame
    spec = instrument.spec()
    if spec is None:
        raise UserError("bridge.format", format=name[:40], known=", ".join(FORMATS))
    decoder = FrameDecoder(spec, instrument.axis, instrument.temperature_scale)
    unit = instrument.unit or spec.unit
    if unit is None:
        raise UserError("bridge.spec_needs_unit")
    rate = instrument.rate_hz or spec.rate_hz
    return Setup(decoder, unit, rate, spec.get("temp") is not None)
