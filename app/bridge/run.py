"""One bridge run: bytes → frames → samples → the session (and a raw recording, and a
CSV of the samples), with a report of what the line did."""

from __future__ import annotations

import csv
import time
from collections.abc import Callable, Iterable
from dataclasses import dataclass, field
from pathlib import Path
from typing import TextIO

from app.bridge.frames import LinkStats
from app.bridge.instruments import Setup
from app.bridge.lines import TextDecoder
from app.bridge.recording import Recorder
from app.bridge.samples import Sample, SampleMaker
from app.bridge.upload import Uploader
from app.core.exceptions import UserError

PROGRESS_EVERY_S = 0.5


class SampleTable:
    """The samples as a CSV in GyroLab's long layout (``position,time_s,value,
    temperature_c``, value in °/h), appended to, so that one file can collect every
    position of a run for ``gyrolab solve``."""

    def __init__(self, path: Path, position: int, *, timed: bool, temperature: bool) -> None:
        columns = ["position"] + (["time_s"] if timed else []) + ["value"]
        columns += ["temperature_c"] if temperature else []
        self.position = position
        self.timed, self.temperature = timed, temperature
        try:
            existing = path.read_text(encoding="utf-8").splitlines()[:1] if path.exists() else []
            if existing and existing[0].strip() != ",".join(columns):
                raise UserError(
                    "bridge.csv_columns",
                    path=str(path),
                    columns=existing[0][:80],
                )
            self._file: TextIO = path.open("a", encoding="utf-8", newline="")
        except OSError as error:
            raise UserError("bridge.cannot_write", path=str(path), error=error.strerror) from None
        self._writer = csv.writer(self._file, lineterminator="\n")
        if not existing:
            self._writer.writerow(columns)

    def write(self, samples: list[Sample]) -> None:
        for sample in samples:
            row: list = [self.position]
            if self.timed:
                row.append(f"{sample.time_s:.6f}")
            row.append(repr(sample.rate_deg_h))
            if self.temperature:
                temperature = sample.temperature_c
                row.append("" if temperature is None else f"{temperature:.2f}")
            self._writer.writerow(row)

    def close(self) -> None:
        self._file.close()


@dataclass
class Outcome:
    """What a run did, for the closing report."""

    stats: LinkStats
    samples: int = 0
    stored: int = 0
    gaps: int = 0
    absent: int = 0
    counted: bool = True  # the format shows gaps (a counter, or a fixed output period)
    truncated: bool = False
    temperatures: list[float] = field(default_factory=list)  # lowest, highest

    @property
    def gapped(self) -> bool:
        return self.absent > 0


def run_bridge(
    chunks: Iterable[tuple[float, bytes]],
    setup: Setup,
    maker: SampleMaker,
    *,
    uploader: Uploader | None = None,
    recorder: Recorder | None = None,
    table: SampleTable | None = None,
    max_samples: int | None = None,
    seconds: float | None = None,
    progress: Callable[[Outcome, int | None, int], None] | None = None,
) -> Outcome:
    """Read, decode, convert and send until the input ends or a limit is reached.

    ``seconds`` is measured on the source's clock (a replay's recorded time);
    ``progress(outcome, stored, absent)`` is called at most twice a second.  Samples
    beyond ``max_samples`` are not sent.  Ctrl-C ends the run like the end of the input
    (what was made is sent); the files are closed whatever happens.
    """
    decoder = setup.decoder
    outcome = Outcome(decoder.stats, counted=setup.rate_hz is not None and _counts(setup))
    shown = time.monotonic()
    try:
        for at, chunk in chunks:
            if recorder is not None:
                recorder.write(at, chunk)
            samples = maker.make(decoder.feed(chunk)) if chunk else []
            if max_samples is not None:
                samples = samples[: max(max_samples - outcome.samples, 0)]
            _take(samples, outcome, uploader, table)
            if progress is not None and time.monotonic() - shown >= PROGRESS_EVERY_S:
                shown = time.monotonic()
                progress(outcome, uploader.sent if uploader else None, maker.absent)
            if max_samples is not None and outcome.samples >= max_samples:
                break
            if seconds is not None and at >= seconds:
                break
        if uploader is not None:
            uploader.flush()
    except KeyboardInterrupt:
        if uploader is not None:
            uploader.flush()
    finally:
        if uploader is not None:
            outcome.stored = uploader.sent
        if recorder is not None:
            recorder.close()
        if table is not None:
            table.close()
        outcome.gaps, outcome.absent = maker.gaps, maker.absent
    return outcome


def _counts(setup: Setup) -> bool:
    """Gaps are visible: the frames carry a counter, or come one per fixed period."""
    return not isinstance(setup.decoder, TextDecoder)


def _take(
    samples: list[Sample], outcome: Outcome, uploader: Uploader | None, table: SampleTable | None
) -> None:
    if not samples:
        return
    outcome.samples += len(samples)
    temperatures = [s.temperature_c for s in samples if s.temperature_c is not None]
    if temperatures:
        low, high = min(temperatures), max(temperatures)
        if outcome.temperatures:
            low, high = min(low, outcome.temperatures[0]), max(high, outcome.temperatures[1])
        outcome.temperatures = [low, high]
    if table is not None:
        table.write(samples)
    if uploader is not None:
        for sample in samples:
            uploader.add(sample.rate_deg_h, sample.time_s, sample.temperature_c)
