"""Rendered report PDFs kept per process, so that a report is laid out once per content.

The key is what the PDF shows: a digest of the report's HTML in its language with the
"generated at" time left out and the figures not drawn, of what the figures are drawn
from (readings, times, fit), and of the takes behind it (id, trim -- so the samples
attached to a long record are covered too).  Any change that shows -- new data, a
trimmed take, the discussion, a returned review, a released grade, a partner joining,
the truth revealed -- makes a new key, so a cached PDF is never stale and no caller has to
remember to invalidate it.  Keying costs milliseconds (the figures' drawing, most of a
report's HTML, is left to the render); WeasyPrint's layout seconds (bench/README.md,
"Reports").  Bounded in bytes (``GYROLAB_REPORT_CACHE_MB``)."""

from __future__ import annotations

import hashlib
import threading
from collections import OrderedDict
from dataclasses import replace
from datetime import UTC, datetime

from app.reports.content import Report
from app.reports.figures import figure_inputs
from app.reports.pdf import report_html

KEY_TIME = datetime(2000, 1, 1, tzinfo=UTC)  # the "generated at" the key is computed with


def content_key(report: Report, language: str) -> str:
    """The digest of what ``report`` shows in ``language`` (not when it was rendered)."""
    digest = hashlib.sha256()
    digest.update(f"{report.session.id}|{language}|{report.take_keys!r}|".encode())
    for part_result in report.results.values():
        digest.update(hashlib.sha256(figure_inputs(part_result)).digest())
    shown = replace(report, generated_at=KEY_TIME)
    digest.update(report_html(shown, language, draw_figures=False).encode())
    return digest.hexdigest()


class PdfCache:
    """A thread-safe LRU of PDF bytes by :func:`content_key`, at most ``max_bytes``."""

    def __init__(self, max_bytes: int) -> None:
        self.max_bytes = max_bytes
        self._entries: OrderedDict[str, bytes] = OrderedDict()
        self._lock = threading.Lock()
        self.hits = self.misses = 0

    def get(self, key: str) -> bytes | None:
        with self._lock:
            content = self._entries.get(key)
            if content is None:
                self.misses += 1
                return None
            self._entries.move_to_end(key)
            self.hits += 1
            return content

    def put(self, key: str, content: bytes) -> None:
        if len(content) > self.max_bytes:
            return
        with self._lock:
            self._entries[key] = content
            self._entries.move_to_end(key)
            while sum(map(len, self._entries.values())) > self.max_bytes:
                self._entries.popitem(last=False)

    def clear(self) -> None:
        with self._lock:
            self._entries.clear()
            self.hits = self.misses = 0


_cache: PdfCache | None = None
_cache_lock = threading.Lock()


def pdf_cache() -> PdfCache:
    """The process's cache, sized from the settings on first use."""
    global _cache
    with _cache_lock:
        if _cache is None:
            from app.config import get_settings

            _cache = PdfCache(get_settings().report_cache_mb * 2**20)
        return _cache
