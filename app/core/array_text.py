"""A MATLAB data file's or a NumPy file's table of readings as text, for the readers of a
position's record that the lab page's file panel uses.

A student who logs the gyro from MATLAB saves ``t`` and ``omega`` (or an IMU's matrix)
to a ``.mat`` file; a Python script saves ``np.save`` or ``np.savez``.  The file's longest
vectors (:func:`app.core.array_files.array_table`) become the columns of a table whose
header is a comment line above the readings, as EuRoC's records have it -- so it is read
as one position's record, never as a table of positions -- with the times' column named
``time (s)``: the file's own (``t``, ``time``), or those its stated rate gives
(``k / Fs``).  Vectors named for their positions (``p1`` … ``p4``, as a student keeps
the handout's table in MATLAB), a file's one matrix of four or eight columns and nothing
else, and a ``.npy`` of four or eight columns are written as the handout's wide table
instead, read as the positions they hold.  The numbers are written as the shortest text
that reads back as the same float64, so the readings stored are the file's.
"""

from __future__ import annotations

import re

import numpy as np

from app.core.array_files import ArrayTable, array_table
from app.core.exceptions import UserError
from app.core.matlab_files import is_matlab_file, matlab_variables
from app.core.numpy_files import is_npy, is_npz, numpy_arrays

# the fewest numbers a vector has to be a column: the lab's own check of a position's
# readings then asks for its minimum (10), in its words
MIN_POSITION_READINGS = 2
POSITION_COUNTS = (4, 8)  # a table's columns: the four positions, or the symmetric eight
MAX_NUMBERS = 600_000  # numbers written, at most: ≈ 12 MB of text, twice a file's 5 MB
TIME_HEADER = "time (s)"
# a .npy's columns, by its shape's second length (the REST API's layouts)
NPY_HEADERS = {1: ("rate",), 2: (TIME_HEADER, "rate"), 3: (TIME_HEADER, "rate", "temperature (°C)")}
_NOT_IN_A_NAME = re.compile(r"[\s#,;]+")  # what would split a header cell, or start one
# a vector named for its position: p1, P3, pos2, pos_4, position1, position_8
_POSITION_NAME = re.compile(r"(?:p|pos|position)_?([1-8])", re.IGNORECASE)


def is_array_file(data: bytes) -> bool:
    """Whether a file is a MATLAB data file, a ``.npy`` array or a ``.npz`` archive.

    Parameters
    ----------
    data : bytes
        The whole file (an archive is told from a workbook by its members).

    Returns
    -------
    bool
        True for any of the three.
    """
    return is_matlab_file(data[:20]) or is_npy(data[:6]) or is_npz(data)


def array_file_text(data: bytes) -> str:
    """The file's table of readings as tab-separated text under a ``#`` header line.

    Parameters
    ----------
    data : bytes
        A MATLAB data file, a ``.npy`` array or a ``.npz`` archive (:func:`is_array_file`).

    Returns
    -------
    str
        ``#time (s)<TAB>omega`` (the vectors' names; a matrix's columns ``name 1``, …),
        then a line per reading; for vectors named for positions, ``position_1<TAB>…``
        over a row per reading.

    Raises
    ------
    UserError
        Those of :func:`app.core.matlab_files.matlab_variables`,
        :func:`app.core.numpy_files.numpy_arrays` and
        :func:`app.core.array_files.array_table`; ``numpy.shape`` for a ``.npy`` that is
        not ``(n,)``, ``(n, 2)``, ``(n, 3)``, ``(n, 4)`` or ``(n, 8)`` numbers;
        ``arrays.too_many_numbers`` past
        :data:`MAX_NUMBERS`.
    """
    if is_matlab_file(data[:20]):
        variables, kind = matlab_variables(data), "matlab"
    else:
        loaded = numpy_arrays(data)
        if not isinstance(loaded, dict):
            return _npy_text(loaded)
        variables, kind = loaded, "numpy"
    positions = _position_vectors(variables) or _position_matrix(variables)
    if positions:
        return _positions_text(positions)
    return _table_text(array_table(variables, kind, MIN_POSITION_READINGS))


def _position_matrix(variables: dict) -> dict[int, np.ndarray]:
    """The file's one matrix of four or eight columns (or rows), where it holds nothing
    else -- no other vector, no times, no sample rate: the handout's table as a student
    keeps it in MATLAB (``A = [10.74 2.88 -9.11 -0.96; …]``), a column a position.  An
    IMU's record states its rate or times, or has other than four or eight axes."""
    arrays = []
    for value in variables.values():
        array = np.squeeze(np.asarray(value))
        if array.dtype.kind not in "fiu" or array.size == 0:
            continue
        if array.ndim == 0 or array.size == 1:
            return {}  # a scalar: a sample rate, most likely
        arrays.append(array)
    if len(arrays) != 1 or arrays[0].ndim != 2:
        return {}
    matrix = arrays[0]
    if matrix.shape[1] not in POSITION_COUNTS or matrix.shape[0] < matrix.shape[1]:
        matrix = matrix.T  # positions as rows
    if matrix.shape[1] not in POSITION_COUNTS or matrix.shape[0] < matrix.shape[1]:
        return {}
    return {k + 1: matrix[:, k].astype(float) for k in range(matrix.shape[1])}


def _position_vectors(variables: dict) -> dict[int, np.ndarray]:
    """The file's vectors named for the positions they were read at (``p1`` … ``p4``,
    ``pos3``, ``position_2``; a struct's ``heading.p1``), where there are three or more
    and no two name one position; else none."""
    found: dict[int, np.ndarray] = {}
    for name, value in variables.items():
        named = _POSITION_NAME.fullmatch(name.rsplit(".", 1)[-1])
        array = np.asarray(value)
        if named is None or array.dtype.kind not in "fiu" or array.size < MIN_POSITION_READINGS:
            continue
        if np.squeeze(array).ndim != 1 or int(named.group(1)) in found:
            return {}
        found[int(named.group(1))] = np.squeeze(array).astype(float)
    return dict(sorted(found.items())) if len(found) >= 3 else {}


def _positions_text(positions: dict[int, np.ndarray]) -> str:
    """Vectors of positions as the handout's wide table: ``position_1 …`` over a row per
    reading, a shorter position's cells left empty -- read as a table of positions."""
    count = sum(values.size for values in positions.values())
    if count > MAX_NUMBERS:
        raise UserError("arrays.too_many_numbers", count=count, limit=MAX_NUMBERS)
    longest = max(values.size for values in positions.values())
    cells = [
        list(values.astype(str)) + [""] * (longest - values.size) for values in positions.values()
    ]
    header = "\t".join(f"position_{number}" for number in positions)
    return "\n".join([header, *("\t".join(row) for row in zip(*cells, strict=True))]) + "\n"


def _npy_text(array: np.ndarray) -> str:
    """A ``.npy``'s columns: readings; time and readings; and case temperatures -- or,
    four or eight columns, the handout's table of positions."""
    if array.dtype.kind in "fiu" and array.ndim == 2 and array.shape[1] in POSITION_COUNTS:
        return _positions_text({k + 1: array[:, k].astype(float) for k in range(array.shape[1])})
    if array.ndim == 1:
        array = array[:, None]
    if array.dtype.kind not in "fiu" or array.ndim != 2 or array.shape[1] not in NPY_HEADERS:
        raise UserError("numpy.shape", shape=str(tuple(array.shape)))
    columns = [array[:, k].astype(float) for k in range(array.shape[1])]
    return _text(NPY_HEADERS[array.shape[1]], columns)


def _table_text(table: ArrayTable) -> str:
    """The vectors as columns, the times first; times from the stated rate where the file
    has none."""
    length = next(iter(table.columns.values())).size
    names = [_header_cell(name) for name in table.offered]
    columns = [table.columns[name] for name in table.offered]
    if table.time is not None:
        return _text([TIME_HEADER, *names], [table.columns[table.time], *columns])
    if table.rate_hz:
        return _text([TIME_HEADER, *names], [np.arange(length) / table.rate_hz, *columns])
    return _text(names, columns)


def _header_cell(name: str) -> str:
    """A vector's name as a header cell: nothing in it that splits a cell or starts one."""
    return _NOT_IN_A_NAME.sub(" ", name).strip() or "rate"


def _text(header, columns: list[np.ndarray]) -> str:
    count = len(columns) * columns[0].size
    if count > MAX_NUMBERS:
        raise UserError("arrays.too_many_numbers", count=count, limit=MAX_NUMBERS)
    cells = [column.astype(str) for column in columns]  # the shortest that reads back
    lines = ["#" + "\t".join(header), *("\t".join(row) for row in zip(*cells, strict=True))]
    return "\n".join(lines) + "\n"
