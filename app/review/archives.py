"""Readings of earlier years, uploaded by a teacher so that copies of them are found
(``app/review/earlier_copies.py``): a class zip as GyroLab exports it (``<group>/attempt-
<n>.csv``) or one readings CSV (``part,position,…,source,…,value``).  Only the readings'
copy keys are kept -- not the readings, not the names beyond the group's label."""

from __future__ import annotations

import csv
import io
import re
import zipfile
from collections.abc import Iterable, Iterator
from dataclasses import dataclass
from typing import BinaryIO

import numpy as np
from fastapi import UploadFile
from sqlmodel import Session, col, delete, func, select

from app.core.data_copies import copy_keys
from app.core.exceptions import UserError
from app.lab.copy_index import MIN_OWN_POSITIONS
from app.models import CopyKey, InputMethod, ReadingArchive
from app.web.work_slots import pool

MAX_MEMBERS = 20_000  # CSV files in one zip
MAX_UNPACKED = 256 * 1024 * 1024  # bytes of CSV read from one upload
MAX_NAME = 200
ENCRYPTED = 0x1  # a zip member's general-purpose flag: encrypted (PKWARE's APPNOTE 4.4.4)
ATTEMPT_FILE = re.compile(r"(?:^|/)([^/]+)/attempt-(\d{1,6})\.csv$")
PARTS = ("heading", "latitude")


@dataclass
class ArchivedGroup:
    """One group's attempt in the upload: its label, attempt number, part → keys."""

    label: str
    attempt: int | None
    keys: dict[str, list[str]]


def readings_keys(lines: Iterable[str]) -> dict[str, list[str]]:
    """part → copy keys of a readings CSV's parts recorded by the students (≥ 3 positions
    not from the simulated gyro); rows that are not readings are passed over."""
    reader = csv.reader(line for line in lines if not line.startswith("#") and line.strip())
    header = [cell.strip().lower() for cell in next(reader, [])]
    if not {"part", "position", "value"} <= set(header):
        return {}
    at = {name: header.index(name) for name in ("part", "position", "value")}
    source_at = header.index("source") if "source" in header else None
    positions: dict[str, dict[int, list[float]]] = {}
    simulated: set[tuple[str, int]] = set()
    for row in reader:
        try:
            part, position = row[at["part"]].strip(), int(row[at["position"]])
            value = float(row[at["value"]])
        except (IndexError, ValueError):
            continue
        if part not in PARTS or not np.isfinite(value):
            continue
        positions.setdefault(part, {}).setdefault(position, []).append(value)
        source = row[source_at] if source_at is not None and len(row) > source_at else ""
        if source.strip().lstrip("'") == InputMethod.simulator:
            simulated.add((part, position))
    out = {}
    for part, by_position in positions.items():
        own = [np.array(by_position[k]) for k in sorted(by_position) if (part, k) not in simulated]
        keys = copy_keys(own) if len(own) >= MIN_OWN_POSITIONS else []
        if keys:
            out[part] = keys
    return out


def _file_keys(handle: BinaryIO, where: str) -> dict[str, list[str]]:
    text = io.TextIOWrapper(handle, encoding="utf-8-sig", newline="")
    try:
        return readings_keys(text)
    except UnicodeDecodeError:
        raise UserError("archive.not_utf8", file=where[:MAX_NAME]) from None
    except csv.Error:
        raise UserError("archive.bad_csv", file=where[:MAX_NAME]) from None
    finally:
        text.detach()


def _zip_groups(handle: BinaryIO) -> Iterator[ArchivedGroup]:
    try:
        archive = zipfile.ZipFile(handle)
    # NotImplementedError: a zip version the module does not read ("zip file version 8.5")
    except (zipfile.BadZipFile, OSError, ValueError, EOFError, NotImplementedError):
        raise UserError("archive.bad_zip") from None
    members = [info for info in archive.infolist() if ATTEMPT_FILE.search(info.filename)]
    if any(info.flag_bits & ENCRYPTED for info in members):  # a zip behind a password
        raise UserError("archive.encrypted")
    if len(members) > MAX_MEMBERS:
        raise UserError("archive.too_many", limit=MAX_MEMBERS)
    # a member never yields more than its stated size (zipfile stops there)
    if sum(info.file_size for info in members) > MAX_UNPACKED:
        raise UserError("archive.too_big", limit=MAX_UNPACKED // 2**20)
    for info in members:
        match = ATTEMPT_FILE.search(info.filename)
        try:
            with archive.open(info) as member:
                keys = _file_keys(member, info.filename)
        except NotImplementedError:  # a compression method the module does not read
            raise UserError("archive.compression", file=info.filename[:MAX_NAME]) from None
        except (zipfile.BadZipFile, OSError, EOFError, RuntimeError):
            raise UserError("archive.bad_zip") from None
        if keys:
            yield ArchivedGroup(match.group(1)[:MAX_NAME], int(match.group(2)), keys)


def read_archive(name: str, handle: BinaryIO) -> list[ArchivedGroup]:
    """The groups of an uploaded file (a class zip or one readings CSV) with their keys.

    Raises
    ------
    UserError
        Not a zip or a UTF-8 CSV, too large, or no readings a student recorded in it.
    """
    head = handle.read(4)
    handle.seek(0)
    if not head:
        raise UserError("archive.no_file")
    if head.startswith(b"PK"):
        groups = list(_zip_groups(handle))
    else:
        stem = re.sub(r"\.csv$", "", name.rsplit("/", 1)[-1], flags=re.I).strip() or "—"
        keys = _file_keys(handle, stem)
        groups = [ArchivedGroup(stem[:MAX_NAME], None, keys)] if keys else []
    if not groups:
        raise UserError("archive.no_readings")
    return groups


def store_archive(
    db: Session, teacher_id: int, name: str, groups: list[ArchivedGroup]
) -> ReadingArchive:
    """Keep an upload's keys under the teacher (they are matched only in their courses)."""
    archive = ReadingArchive(
        teacher_id=teacher_id, name=(name.strip() or "—")[:MAX_NAME], groups=len(groups)
    )
    db.add(archive)
    db.flush()
    for group in groups:
        for part, keys in group.keys.items():
            for key in keys:
                db.add(
                    CopyKey(
                        key=key,
                        part=part,
                        archive_id=archive.id,
                        label=group.label,
                        attempt=group.attempt,
                    )
                )
    return archive


def upload_archive(db: Session, teacher_id: int, upload: UploadFile | None) -> ReadingArchive:
    """An uploaded file (the page's form and ``POST /api/v1/archives`` share this): read in
    the teacher's analysis slot, its keys kept under the teacher.  Nothing is stored when
    the file is refused (the caller commits).

    Raises
    ------
    UserError
        No file, or the file is refused (:func:`read_archive`).
    """
    if upload is None:
        raise UserError("archive.no_file")
    name = upload.filename or ""
    with pool("analysis").slot(teacher_id):
        groups = read_archive(name, upload.file)
    return store_archive(db, teacher_id, name, groups)


def teacher_archives(db: Session, teacher_id: int) -> list[ReadingArchive]:
    return list(
        db.exec(
            select(ReadingArchive)
            .where(ReadingArchive.teacher_id == teacher_id)
            .order_by(ReadingArchive.uploaded_at.desc(), ReadingArchive.id.desc())
        ).all()
    )


def archive_count(db: Session, teacher_id: int) -> int:
    return db.exec(
        select(func.count())
        .select_from(ReadingArchive)
        .where(ReadingArchive.teacher_id == teacher_id)
    ).one()


def delete_archive(db: Session, teacher_id: int, archive_id: int) -> None:
    """Forget an upload's keys (only the teacher's own; another's is "not found")."""
    archive = db.get(ReadingArchive, archive_id)
    if archive is None or archive.teacher_id != teacher_id:
        raise UserError("archive.not_found", status=404)
    # one statement for the keys, before the archive row: the ORM, knowing no link between
    # the two, could delete the archive first, whose ON DELETE CASCADE took the keys
    db.exec(delete(CopyKey).where(col(CopyKey.archive_id) == archive.id))
    db.delete(archive)
