"""Gyros that print lines of text: any instrument read by regular expression or column
(``--format text``), the KVH DSP-3000's ASCII output (``--format kvh-dsp3000``) and a
VectorNav's asynchronous ASCII sentences (``--format vectornav``).

Both split the byte stream into lines themselves, so a line longer than the limit (a
line with its end lost, or binary noise) is dropped and counted, never buffered without
bound.
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass

from app.bridge.frames import Frame, LinkStats
from app.core.sentence_records import FIELDS, SENTENCE, checksum_holds

MAX_LINE_BYTES = 4096
# "(-)xxx.xxxxxx y": the reading, then 1 (valid) or 0 (fault); KVH DSP-3000 manual, RS-232
DSP3000_LINE = re.compile(rb"^\s*([-+]?\d+(?:\.\d*)?(?:[eE][-+]?\d+)?)\s+([01])\s*$")


@dataclass
class LineParser:
    """A reading from one line of text: a regular expression's first group (or the group
    named ``value``), or a column (1-based, split on commas, semicolons or white space),
    times ``scale``."""

    regex: re.Pattern | None = None
    column: int | None = None
    scale: float = 1.0
    skipped: int = 0

    def parse(self, line: str) -> float | None:
        text = line.strip()
        if not text:
            return None
        try:
            if self.regex is not None:
                match = self.regex.search(text)
                if match is None:
                    raise ValueError
                groups = match.groupdict()
                raw = groups.get("value") or (match.group(1) if match.groups() else match.group(0))
            else:
                cells = [c for c in re.split(r"[,;\s]+", text) if c]
                raw = cells[(self.column or 1) - 1]
            value = float(raw) * self.scale
        except (ValueError, IndexError):
            self.skipped += 1
            return None
        if not math.isfinite(value):
            self.skipped += 1
            return None
        return value


class LineSplitter:
    """Whole lines out of byte chunks.  The first piece (the instrument was mid-line when
    the port opened) and any line over ``limit`` bytes are counted as garbage."""

    def __init__(self, stats: LinkStats, limit: int = MAX_LINE_BYTES) -> None:
        self.stats = stats
        self.limit = limit
        self._partial = bytearray()
        self._started = False
        self._overflowed = False

    def lines(self, chunk: bytes) -> list[bytes]:
        pieces = chunk.split(b"\n")
        complete: list[bytes] = []
        for index, piece in enumerate(pieces):
            last = index == len(pieces) - 1
            if self._overflowed:
                if last:
                    self.stats.garbage_bytes += len(piece)
                    continue
                self.stats.garbage_bytes += len(piece) + 1
                self._overflowed = False
                self._started = True
                continue
            self._partial += piece
            if last:
                if len(self._partial) > self.limit:
                    self.stats.garbage_bytes += len(self._partial)
                    self._partial.clear()
                    self._overflowed = True
                break
            line = bytes(self._partial)
            self._partial.clear()
            if len(line) > self.limit:
                self.stats.garbage_bytes += len(line) + 1
                self._started = True
                continue
            if not self._started:
                self._started = True
                self.stats.garbage_bytes += len(line) + 1
                continue
            complete.append(line)
        return complete

    def start_mid_line(self, value: bool) -> None:
        """Whether the stream may begin mid-line (a serial port: yes; a file: no)."""
        self._started = not value


class TextDecoder:
    """``--format text``: each line that parses is one reading; other lines (status
    sentences, headers) are skipped and counted.  Lines carry no counter."""

    def __init__(self, parser: LineParser, *, mid_line: bool = True) -> None:
        self.parser = parser
        self.stats = LinkStats()
        self._splitter = LineSplitter(self.stats)
        self._splitter.start_mid_line(mid_line)
        self._count = -1

    def feed(self, chunk: bytes) -> list[Frame]:
        frames = []
        for line in self._splitter.lines(chunk):
            value = self.parser.parse(line.decode("utf-8", errors="replace"))
            if value is not None:
                self._count += 1
                self.stats.frames += 1
                frames.append(Frame(self._count, value))
        return frames


class Dsp3000Decoder:
    """``--format kvh-dsp3000``: lines ``(-)xxx.xxxxxx y`` at the gyro's fixed rate.

    The format has no counter: every line is one output period, so a line with ``y = 0``
    (fault) or one that does not parse (corrupted on the line) is dropped and leaves a
    one-sample gap; a line lost whole cannot be seen.
    """

    def __init__(self, *, mid_line: bool = True) -> None:
        self.stats = LinkStats()
        self._splitter = LineSplitter(self.stats, limit=64)
        self._splitter.start_mid_line(mid_line)
        self._count = -1

    def feed(self, chunk: bytes) -> list[Frame]:
        frames = []
        stats = self.stats
        for line in self._splitter.lines(chunk):
            if not line.strip():
                continue
            self._count += 1
            match = DSP3000_LINE.match(line)
            if match is None:
                stats.corrupt += 1
                stats.missing += 1
                continue
            value = float(match.group(1))
            if match.group(2) != b"1" or not math.isfinite(value):
                stats.faults += 1
                continue
            stats.frames += 1
            frames.append(Frame(self._count, value))
        return frames


class SentenceDecoder:
    """``--format vectornav``: a VectorNav's ASCII sentences (``$VNYMR``, ``$VNQMR``,
    ``$VNIMU``), one per output period at the rate it was set to, the chosen axis's rate
    in rad/s (``$VNIMU``'s temperature too).

    The sentences carry no counter: as for the DSP-3000's lines, every sentence of the
    kind is one output period, so one whose checksum fails (or that is cut) is dropped
    and leaves a one-sample gap; a sentence of another kind (a reply to a command,
    ``$VNERR``) is skipped and counted, not a period.
    """

    def __init__(self, axis: str, *, mid_line: bool = True) -> None:
        self.axis = axis
        self.stats = LinkStats()
        self._splitter = LineSplitter(self.stats, limit=512)
        self._splitter.start_mid_line(mid_line)
        self._count = -1
        self._kind: str | None = None

    def feed(self, chunk: bytes) -> list[Frame]:
        frames = []
        stats = self.stats
        for line in self._splitter.lines(chunk):
            text = line.decode("ascii", errors="replace").strip()
            if not text:
                continue
            found = SENTENCE.fullmatch(text)
            kind = found["kind"] if found is not None else None
            if kind is not None and self._kind is None and kind in FIELDS:
                self._kind = kind  # the first sentence with angular rates sets the kind
            if kind is not None and kind != self._kind:
                stats.garbage_bytes += len(line) + 1  # another output, or a reply
                continue
            self._count += 1
            if found is None or (found["check"] and not checksum_holds(text, found["check"])):
                stats.corrupt += 1
                stats.missing += 1
                continue
            names = FIELDS[self._kind]
            cells = found["body"].split(",")
            try:
                value = float(cells[names.index(f"gyro_{self.axis} (rad/s)")])
                temperature = (
                    float(cells[names.index("temperature (°C)")])
                    if "temperature (°C)" in names
                    else None
                )
            except (ValueError, IndexError):
                stats.corrupt += 1
                stats.missing += 1
                continue
            if not math.isfinite(value):
                stats.corrupt += 1
                stats.missing += 1
                continue
            stats.frames += 1
            frames.append(Frame(self._count, value, temperature))
        return frames
