"""Fixed binary frames: their description (a one-line mini-language or a TOML file) and a
decoder that survives a real serial line.

The mini-language (``--format frame:SPEC``) is a comma-separated list of settings
``key=value`` and fields ``name:type[*scale][&mask][!mask][%modulus]``, in frame order
after the header::

    hdr=99 66, z:<i4*0.0001, temp:<i2*0.01, seq:u1, check=sum8@2, rate=200, unit=deg/s

settings
    ``hdr`` the header bytes in hex (required); ``check`` one of sum8, xor8, crc16-ccitt,
    crc32-mpeg2, placed after the fields and covering the frame from byte ``@START``
    (default 0, the header included); ``rate`` the output rate in Hz; ``unit`` what the
    axis fields hold: a rate (deg/h, deg/s, rad/s) or an angle increment per frame
    (deg, rad, arcsec).
fields
    ``x``, ``y``, ``z`` the gyro axes; ``temp`` the temperature in °C after scaling;
    ``seq`` a frame counter (wraps at ``%modulus``, default 2⁸ⁿ for n bytes); ``status``
    a flags byte: the frame is valid only with every ``&mask`` bit set and every
    ``!mask`` bit clear; ``_`` bytes to skip.  Types: ``i1 u1 i2 u2 i3 u3 i4 u4 f4 f8``,
    prefixed ``>`` big-endian (the default) or ``<`` little-endian; a bare number is that
    many bytes to skip.

A TOML file (``--format frame:gyro.toml``) holds the same: ``header``, ``checksum``,
``checksum_from``, ``rate_hz``, ``unit`` and ``fields`` (a list of field strings).
"""

from __future__ import annotations

import re
import struct
import tomllib
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path

from app.bridge.checksums import CHECKSUMS, Checksum
from app.core.exceptions import UserError

MAX_RATE_HZ = 1.0e6  # the highest output rate the bridge takes (a FOG's is ≤ 10 kHz)

AXES = ("x", "y", "z")
ROLES = (*AXES, "temp", "seq", "status", "_")
RATE_UNITS = ("deg/h", "deg/s", "rad/s")
ANGLE_UNITS = ("deg", "rad", "arcsec")
MAX_FRAME_BYTES = 1024
FIELD = re.compile(
    r"^(?P<name>[a-z_]+):(?P<type>[<>]?[iuf]\d|\d+)"
    r"(?:\*(?P<scale>[-+0-9.eE]+))?(?P<flags>(?:[&!%](?:0x[0-9a-fA-F]+|\d+))*)$"
)
FLAG = re.compile(r"([&!%])(0x[0-9a-fA-F]+|\d+)")
STRUCT_CODES = {"i1": "b", "u1": "B", "i2": "h", "u2": "H", "i4": "i", "u4": "I", "f4": "f"}
STRUCT_CODES["f8"] = "d"


def spec_error(problem: str, **params: object) -> UserError:
    return UserError(f"bridge.spec_{problem}", **params)


@dataclass(frozen=True)
class Field:
    """One field of a frame: where it is, how to read it and what it means."""

    name: str
    offset: int
    size: int
    read: Callable[[bytes | bytearray | memoryview, int], float] = field(repr=False)
    scale: float = 1.0
    must_set: int = 0
    must_clear: int = 0
    modulus: int = 0


@dataclass(frozen=True)
class FrameSpec:
    """A fixed frame: header, fields, optional checksum, and what the axes hold."""

    header: bytes
    fields: tuple[Field, ...]
    length: int
    checksum: Checksum | None = None
    checksum_from: int = 0
    unit: str | None = None
    rate_hz: float | None = None
    axis_status_bits: dict[str, int] = field(default_factory=dict)  # KVH: one bit per axis

    def get(self, name: str) -> Field | None:
        return next((f for f in self.fields if f.name == name), None)

    @property
    def axes(self) -> list[str]:
        return [f.name for f in self.fields if f.name in AXES]


def _reader(kind: str) -> tuple[int, Callable]:
    """(size, read(buffer, offset)) for a type such as ``>i4``, ``<u3`` or ``f4``."""
    order = "<" if kind.startswith("<") else ">"
    code = kind.lstrip("<>")
    size = int(code[1])
    if code in STRUCT_CODES:
        unpack = struct.Struct(order + STRUCT_CODES[code]).unpack_from
        return size, lambda buffer, at: unpack(buffer, at)[0]
    if code in ("i3", "u3"):
        signed = code[0] == "i"
        byteorder = "little" if order == "<" else "big"
        return 3, lambda buffer, at: int.from_bytes(buffer[at : at + 3], byteorder, signed=signed)
    raise spec_error("type", type=kind)


def build_spec(
    header: str,
    fields: list[str],
    *,
    checksum: str | None = None,
    checksum_from: int = 0,
    rate_hz: float | None = None,
    unit: str | None = None,
) -> FrameSpec:
    """A FrameSpec from its parts (the mini-language's and the TOML file's common ground)."""
    try:
        head = bytes.fromhex(header.replace("0x", "").replace(",", " "))
    except ValueError:
        raise spec_error("header", header=header[:40]) from None
    if not head:
        raise spec_error("header", header=header[:40])
    offset = len(head)
    parsed: list[Field] = []
    for text in fields:
        match = FIELD.match(text.strip())
        if match is None or match["name"] not in ROLES:
            raise spec_error("field", field=text.strip()[:40])
        kind = match["type"]
        if kind.isdigit():
            size, read = int(kind), (lambda buffer, at: 0.0)
        else:
            size, read = _reader(kind)
        flags = {"&": 0, "!": 0, "%": 0}
        for symbol, number in FLAG.findall(match["flags"] or ""):
            flags[symbol] |= int(number, 0)
        modulus = flags["%"] or (2 ** (8 * size) if match["name"] == "seq" else 0)
        try:
            scale = float(match["scale"]) if match["scale"] else 1.0
        except ValueError:
            raise spec_error("field", field=text.strip()[:40]) from None
        parsed.append(
            Field(match["name"], offset, size, read, scale, flags["&"], flags["!"], modulus)
        )
        offset += size
    names = [f.name for f in parsed if f.name != "_"]
    if len(set(names)) != len(names):
        raise spec_error("repeated")
    if not any(name in AXES for name in names):
        raise spec_error("no_axis")
    check = None
    if checksum:
        check = CHECKSUMS.get(checksum.strip().lower())
        if check is None:
            raise spec_error("checksum", checksum=checksum[:20], known=", ".join(CHECKSUMS))
        if not 0 <= checksum_from < offset:
            raise spec_error("checksum_from", start=checksum_from)
    length = offset + (check.size if check else 0)
    if length > MAX_FRAME_BYTES:
        raise spec_error("too_long", limit=MAX_FRAME_BYTES)
    if unit is not None and unit not in RATE_UNITS + ANGLE_UNITS:
        raise spec_error("unit", unit=unit[:20], known=", ".join(RATE_UNITS + ANGLE_UNITS))
    if rate_hz is not None and not 0 < rate_hz <= MAX_RATE_HZ:
        raise spec_error("rate")
    return FrameSpec(head, tuple(parsed), length, check, checksum_from, unit, rate_hz)


def parse_spec(text: str) -> FrameSpec:
    """The mini-language (see the module), or a ``.toml`` file's path."""
    if text.strip().lower().endswith(".toml"):
        return load_spec_file(Path(text.strip()))
    settings: dict[str, str] = {}
    fields: list[str] = []
    for item in (part.strip() for part in text.split(",")):
        if not item:
            continue
        if "=" in item:
            key, _, value = item.partition("=")
            settings[key.strip().lower()] = value.strip()
        else:
            fields.append(item)
    unknown = set(settings) - {"hdr", "check", "rate", "unit"}
    if unknown:
        raise spec_error("setting", setting=sorted(unknown)[0][:20])
    if "hdr" not in settings:
        raise spec_error("header", header="")
    kind, _, start = settings.get("check", "").partition("@")
    try:
        rate = float(settings["rate"]) if "rate" in settings else None
        checksum_from = int(start) if start else 0
    except ValueError:
        raise spec_error("rate") from None
    return build_spec(
        settings["hdr"],
        fields,
        checksum=kind or None,
        checksum_from=checksum_from,
        rate_hz=rate,
        unit=settings.get("unit"),
    )


def load_spec_file(path: Path) -> FrameSpec:
    """A frame described in TOML: ``header``, ``fields``, ``checksum``, ``checksum_from``,
    ``rate_hz``, ``unit``."""
    try:
        data = tomllib.loads(path.read_text(encoding="utf-8"))
    except OSError as error:
        raise UserError("bridge.cannot_read", path=str(path), error=error.strerror) from None
    except (tomllib.TOMLDecodeError, UnicodeDecodeError) as error:
        raise spec_error("toml", error=str(error)[:120]) from None
    fields = data.get("fields")
    if not isinstance(fields, list) or not all(isinstance(f, str) for f in fields):
        raise spec_error("field", field="fields = [...]")
    try:
        return build_spec(
            str(data.get("header", "")),
            fields,
            checksum=data.get("checksum"),
            checksum_from=int(data.get("checksum_from", 0)),
            rate_hz=float(data["rate_hz"]) if "rate_hz" in data else None,
            unit=data.get("unit"),
        )
    except (TypeError, ValueError) as error:
        if isinstance(error, UserError):
            raise
        raise spec_error("toml", error=str(error)[:120]) from None


@dataclass(slots=True)
class Frame:
    """One decoded output of the gyro."""

    count: int  # the gyro's own frame count since the run's first frame (counter unwrapped)
    value: float  # the chosen axis, in the gyro's unit (a rate or an angle increment)
    temperature_c: float | None = None


@dataclass
class LinkStats:
    """What the line did: frames kept, dropped and missing, bytes skipped to resynchronise."""

    frames: int = 0  # valid frames decoded
    corrupt: int = 0  # frames dropped: checksum wrong, or a line that does not parse
    faults: int = 0  # frames dropped: the gyro flagged them invalid
    missing: int = 0  # frames the gyro's counter says never arrived (or were dropped)
    repeated: int = 0  # frames with the previous frame's counter (dropped)
    garbage_bytes: int = 0  # bytes skipped while looking for the next frame
    resyncs: int = 0  # times the stream lost and found the frame boundary again


class FrameDecoder:
    """Frames out of a byte stream, however it is chunked.

    Locked on, each frame is expected right after the last one.  Otherwise (at the start,
    after garbage, after a bad checksum) the next header is searched for; a candidate
    with a weak check (header and checksum under 4 bytes together) is accepted only
    when the next frame's header follows it.  The buffer never holds more than the last
    chunk plus one frame.
    """

    def __init__(
        self,
        spec: FrameSpec,
        axis: str | None = None,
        temperature_scale: float | None = None,
    ) -> None:
        if axis is not None and spec.get(axis) is None:
            raise UserError(
                "bridge.no_such_axis",
                axis=axis,
                axes=", ".join(spec.axes),
            )
        self.spec = spec
        self.axis = axis if axis is not None else (None if spec.axis_status_bits else spec.axes[0])
        self.stats = LinkStats()
        self._buffer = bytearray()
        self._locked = False
        self._ever_locked = False
        self._last_seq: int | None = None
        self._count = -1
        self._weak = len(spec.header) + (spec.checksum.size if spec.checksum else 0) < 4
        self._seq = spec.get("seq")
        self._status = spec.get("status")
        self._temp = spec.get("temp")
        self._temperature_scale = temperature_scale

    def feed(self, chunk: bytes) -> list[Frame]:
        """Decode every whole frame now in the buffer; keep the rest for the next chunk."""
        buffer = self._buffer
        buffer += chunk
        view = memoryview(buffer)
        header, length = self.spec.header, self.spec.length
        frames: list[Frame] = []
        position, end = 0, len(buffer)
        try:
            while end - position >= length:
                if not buffer.startswith(header, position):
                    position = self._skip_to_header(buffer, position, end)
                    continue
                if not self._check(view, position):
                    if self._locked:
                        self.stats.corrupt += 1
                        self._locked = False
                        if self._seq is None:  # no counter: the bad frame held one sample
                            self._count += 1
                            self.stats.missing += 1
                    self.stats.garbage_bytes += 1
                    position += 1
                    continue
                if not self._locked and self._weak:
                    following = position + length
                    if end - following < len(header):
                        break  # wait for the next header to confirm this frame
                    if not buffer.startswith(header, following):
                        self.stats.garbage_bytes += 1
                        position += 1
                        continue
                if not self._locked:
                    if self._ever_locked:
                        self.stats.resyncs += 1
                    self._locked = self._ever_locked = True
                decoded = self._decode(view, position)
                if decoded is not None:
                    frames.append(decoded)
                position += length
        finally:
            view.release()
        del buffer[:position]
        return frames

    def _skip_to_header(self, buffer: bytearray, position: int, end: int) -> int:
        found = buffer.find(self.spec.header, position + 1)
        if found < 0:
            found = max(position + 1, end - len(self.spec.header) + 1)
        self.stats.garbage_bytes += found - position
        self._locked = False
        return found

    def _check(self, view: memoryview, position: int) -> bool:
        check = self.spec.checksum
        if check is None:
            return True
        body_end = position + self.spec.length - check.size
        expected = int.from_bytes(view[body_end : body_end + check.size], "big")
        return check.compute(view[position + self.spec.checksum_from : body_end]) == expected

    def _decode(self, view: memoryview, position: int) -> Frame | None:
        """The frame's sample, or None when it is dropped (fault flag, repeated counter)."""
        stats = self.stats
        if self._seq is not None:
            seq = int(self._seq.read(view, position + self._seq.offset))
            if self._last_seq is None:
                step = 1
            else:
                step = (seq - self._last_seq) % self._seq.modulus
                if step == 0:
                    stats.repeated += 1
                    return None
                stats.missing += step - 1
            self._last_seq = seq
            self._count += step
        else:
            self._count += 1
        status = self._status
        if status is not None:
            flags = int(status.read(view, position + status.offset))
            if self.axis is None:
                self.axis = next(
                    (a for a, bit in self.spec.axis_status_bits.items() if flags & bit), None
                )
                if self.axis is None:
                    stats.faults += 1
                    return None
            must_set = status.must_set | self.spec.axis_status_bits.get(self.axis, 0)
            if flags & must_set != must_set or flags & status.must_clear:
                stats.faults += 1
                return None
        axis = self.spec.get(self.axis)
        value = axis.read(view, position + axis.offset) * axis.scale
        if value != value or value in (float("inf"), float("-inf")):
            stats.faults += 1
            return None
        temperature = None
        if self._temp is not None:
            scale = self._temperature_scale or self._temp.scale
            temperature = self._temp.read(view, position + self._temp.offset) * scale
        stats.frames += 1
        return Frame(self._count, value, temperature)
