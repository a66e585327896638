"""The page templates' compiled code kept on disk between starts (Jinja's bytecode cache).

A served worker compiles all of GyroLab's page templates before it serves
(``render.compile_templates``): ≈ 0.3 s of CPU at every start of every worker, and of every
server the tests start.  With this cache a start after the first loads each template's
compiled code instead (≈ 20 ms for all of them).

Where: Jinja's own per-user directory in the system's temporary directory
(``_jinja2-cache-<uid>``, made and checked by Jinja as the user's own, mode 0700, not a
link -- nobody else can put code there).  Each file is keyed by the template's name and
absolute path (another checkout has its own) and carries Jinja's and Python's versions and
a checksum of the template's source: a changed template is compiled again.  The key here
also carries what else the compiled code depends on -- GyroLab's version and the
environment's extensions and options -- so that an upgrade that changes the environment and
not a template does not load code compiled for the old one.

A cache that cannot be used is no cache: a directory Jinja finds unsafe or cannot make
(a read-only system) leaves the environment without one, and a file that cannot be written
(a full disk) is skipped -- a page is never refused for it.
"""

from __future__ import annotations

import hashlib
import logging

from jinja2 import Environment, FileSystemBytecodeCache
from jinja2.bccache import Bucket

log = logging.getLogger(__name__)


class TemplateCodeCache(FileSystemBytecodeCache):
    """Jinja's file system bytecode cache, keyed by the environment too, never failing a
    render for a file it cannot write."""

    def __init__(self, environment_key: str, directory: str | None = None) -> None:
        super().__init__(directory, f"__gyrolab_{environment_key}_%s.cache")

    def dump_bytecode(self, bucket: Bucket) -> None:
        try:
            super().dump_bytecode(bucket)
        except OSError as error:  # a full or read-only disk: the page is rendered anyway
            log.warning("template code not cached (%s): %s", bucket.key, error)


def environment_key(environment: Environment, version: str) -> str:
    """A digest of what a template's compiled code depends on besides its source: the
    app's version, the environment's extensions and its syntax and whitespace options."""
    parts = [
        version,
        ",".join(sorted(environment.extensions)),
        repr(
            (
                environment.block_start_string,
                environment.block_end_string,
                environment.variable_start_string,
                environment.variable_end_string,
                environment.comment_start_string,
                environment.comment_end_string,
                environment.line_statement_prefix,
                environment.line_comment_prefix,
                environment.trim_blocks,
                environment.lstrip_blocks,
                environment.newline_sequence,
                environment.keep_trailing_newline,
                environment.optimized,
                getattr(environment, "newstyle_gettext", False),
                environment.autoescape
                if isinstance(environment.autoescape, bool)
                else getattr(environment.autoescape, "__qualname__", "function"),
            )
        ),
    ]
    return hashlib.sha256("\n".join(parts).encode()).hexdigest()[:16]


def use_code_cache(environment: Environment, version: str, directory: str | None = None) -> bool:
    """Give ``environment`` a :class:`TemplateCodeCache` (in ``directory``, else Jinja's
    per-user temporary directory); False, and no cache, where none can be made."""
    try:
        environment.bytecode_cache = TemplateCodeCache(
            environment_key(environment, version), directory
        )
    except (OSError, RuntimeError) as error:  # RuntimeError: Jinja found the directory unsafe
        log.warning("templates compiled at each start (no code cache): %s", error)
        environment.bytecode_cache = None
        return False
    return True
