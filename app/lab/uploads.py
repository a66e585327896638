"""An API upload's body parsed into arrays before any database work: JSON (a
PositionUpload), ``text/csv``, or binary (raw floats or ``.npy``, see binary_upload).  A
problem is kept and raised only after the route's permission checks."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Annotated

import numpy as np
from fastapi import Depends, Request
from fastapi.exceptions import RequestValidationError
from pydantic import ValidationError

from app.core.clock_stamps import epoch_scale
from app.core.exceptions import UserError
from app.core.jsonsafe import loads_finite
from app.core.labview_lvm import is_labview_measurement
from app.core.one_position_records import RECORD_PROBLEMS, parse_one_position_record
from app.core.position_records import parse_position_csv
from app.core.readings import parse_readings_csv
from app.core.text_files import decode_text
from app.core.typed_numbers import parse_decimal
from app.core.units import canonical_unit
from app.lab.binary_upload import is_npy, parse_npy, parse_raw
from app.lab.schemas import PositionUpload

MAX_UPLOAD_BYTES = 32 * 1024 * 1024  # 1e6 samples as JSON text are about 20 MB


async def upload_body(request: Request) -> bytes:
    """The raw body (the only async step of an upload; parsing and storing run on the
    thread pool so that a 20 MB JSON body never stops the event loop)."""
    body = await request.body()
    if len(body) > MAX_UPLOAD_BYTES:
        raise UserError("api.body_too_large", status=413, limit=MAX_UPLOAD_BYTES)
    return body


@dataclass
class UploadMeta:
    """What comes with the samples: their unit, the dial angle, an append's offset."""

    unit: str = "deg/h"
    angle_deg: float | None = None
    offset: int | None = None


@dataclass
class ParsedUpload:
    """An upload parsed before any database work (so that no write transaction waits on
    parsing); a problem is kept and reported after the permission checks."""

    upload: UploadMeta | None = None
    values: np.ndarray | None = None
    times: np.ndarray | None = None
    temperatures: np.ndarray | None = None
    problem: Exception | None = None

    def checked(self) -> ParsedUpload:
        if self.problem is not None:
            raise self.problem
        return self


def parsed_upload(request: Request, body: Annotated[bytes, Depends(upload_body)]) -> ParsedUpload:
    try:
        meta, values, times, temperatures = read_upload(request, body)
    except (UserError, RequestValidationError) as error:
        return ParsedUpload(problem=error)
    return ParsedUpload(meta, values, times, temperatures)


BINARY_TYPES = ("application/octet-stream", "application/x-npy", "application/npy")


Arrays = tuple[np.ndarray, np.ndarray | None, np.ndarray | None]  # values, times, °C


def read_upload(request: Request, body: bytes) -> tuple[UploadMeta, *Arrays]:
    """JSON (a PositionUpload), ``text/csv`` (one value per line, or ``time_s,value``), or
    binary: raw little-endian float64/float32 or ``.npy`` (see binary_upload)."""
    content_type = request.headers.get("content-type", "").split(";")[0].strip().lower()
    if content_type == "text/csv":
        meta = query_meta(request)
        column = request.query_params.get("column")
        if column is not None and not 0 < len(column.strip()) <= 200:
            raise UserError("api.bad_column")
        return meta, *csv_position(body, meta.unit, column)
    if content_type in BINARY_TYPES:
        query = request.query_params
        if is_npy(body, content_type):
            values, times, temperatures = parse_npy(body)
        else:
            values, times, temperatures = parse_raw(body, query.get("dtype"), query.get("columns"))
        return query_meta(request), values, times, temperatures
    if content_type not in ("application/json", ""):
        raise UserError("api.content_type", status=415)
    data = loads_finite(body)
    try:
        upload = PositionUpload.model_validate(data)
    except ValidationError as error:
        raise RequestValidationError(error.errors()) from None
    values, times, temperatures = upload_arrays(upload)
    meta = UploadMeta(upload.unit, upload.angle_deg, upload.offset)
    return meta, values, times, temperatures


def csv_position(body: bytes, unit: str, column: str | None = None) -> Arrays:
    """One position's ``text/csv``: a reading (or ``time_s,value``) per line, else one
    position's record as a gyro's logger writes it -- its clock or ns, a header with
    units, a header behind ``#``, one axis of an IMU's record (``column``;
    :func:`app.core.one_position_records.parse_one_position_record`, as the lab page reads
    such a file).  A record's own problem (a bad line, a unit against the header's,
    several axes and none chosen) is said as such; where neither reads it, the first
    reader's.
    """
    try:
        if column is not None or is_labview_measurement(body[:200].decode("utf-8", "ignore")):
            # a column chosen, or LabVIEW's file: the record's reader, which knows them
            raise UserError("csv.not_a_record")
        values, times = parse_position_csv(body, unit, as_named=True)
        if times is None:
            return values, times, None
        if epoch_scale(float(times[0])) is None and bool(np.all(np.diff(times) > 0)):
            return values, times, None
        # times too large for seconds (a clock in ns since 1970), or not rising (a clock
        # coarser than the readings, or "1,234.5" under one name: no times): the record's
        # reader, which spreads a coarse clock's ticks and refuses what is not a record
        raise UserError("csv.not_a_record")
    except UserError as error:
        if error.key in ("csv.encoding", "csv.unit_conflict"):
            raise
        text = decode_text(body)
        try:
            readings = parse_one_position_record(text, unit, column).readings
        except UserError as record_error:
            if record_error.key in RECORD_PROBLEMS:  # a record, with a problem in it
                raise
            count = _positions_in_a_table(text)
            if count > 1:  # the handout's table of every position, to one position's route
                raise UserError("api.table_of_positions", count=count) from None
            raise error from None
    times = readings.times_s[0] if readings.times_s else None
    temperatures = readings.temperatures_c[0] if readings.temperatures_c else None
    return readings.positions[0], times, temperatures


def _positions_in_a_table(text: str) -> int:
    """How many positions a body holds as a table of them (the lab's layouts), else 0."""
    try:
        return len(parse_readings_csv(text).positions)
    except UserError:
        return 0


def query_meta(request: Request) -> UploadMeta:
    """``?unit=``, ``?angle_deg=`` and (appends) ``?offset=`` of a CSV or binary upload."""
    query = request.query_params
    unit = canonical_unit(query.get("unit", "deg/h"))
    try:
        angle = query.get("angle_deg")
        angle_deg = parse_decimal(angle.strip()) if angle is not None else None
    except ValueError:
        raise UserError("api.bad_angle") from None
    offset = query.get("offset")
    if offset is not None and not (offset.isdigit() and len(offset) <= 12):
        raise UserError("api.bad_offset")
    return UploadMeta(unit, angle_deg, int(offset) if offset is not None else None)


def upload_arrays(upload: PositionUpload) -> Arrays:
    values = np.asarray(upload.samples, dtype=float)
    if not np.all(np.isfinite(values)):
        raise UserError("api.samples_not_finite")
    times = None
    if upload.times_s is not None:
        times = np.asarray(upload.times_s, dtype=float)
        if times.size != values.size:
            raise UserError("api.times_count")
        if not np.all(np.isfinite(times)):
            raise UserError("api.times_not_finite")
    temperatures = None
    if upload.temperatures_c is not None:
        temperatures = np.asarray(upload.temperatures_c, dtype=float)
        if temperatures.size != values.size:
            raise UserError("api.temperatures_count")
    return values, times, temperatures


Upload = Annotated[ParsedUpload, Depends(parsed_upload)]
