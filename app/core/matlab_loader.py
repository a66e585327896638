"""MATLAB's loader in a process of its own: ``python -m app.core.matlab_loader`` reads a
``.mat`` file on stdin and writes its numeric variables to stdout as a NumPy ``.npz``
(struct fields as ``struct.field``; text, cells and objects left out).

scipy's reader is compiled code, and a crafted or damaged file can crash it (a bus error
in ``read_var_array``, found by mutating a valid file): in its own process such a crash
ends this process alone, and the caller refuses the file in words
(:func:`app.core.matlab_files.matlab_record`).  The process limits its own memory and
sizes the file's variables before it loads them.

Exit status: 0 read; 3 not readable as a MATLAB file; 4 more than ``MAX_ELEMENTS`` numbers.
"""

from __future__ import annotations

import io
import resource
import sys

MEMORY_BYTES = 4 << 30  # the loader's address space at most
UNREADABLE, TOO_LARGE = 3, 4


def numeric_variables(variables: dict, prefix: str = "", depth: int = 0) -> dict:
    """The variables that are numbers, by name; a struct's fields (nested dicts, as
    ``simplify_cells`` loads them) as ``struct.field``, three levels deep at most.

    Parameters
    ----------
    variables : dict
        As ``scipy.io.loadmat(..., simplify_cells=True)`` returns them.
    prefix : str
        The names' prefix (a struct's name and a dot).
    depth : int
        How deep in structs this is.

    Returns
    -------
    dict
        Name → numpy array of a real number kind.
    """
    import numpy as np

    out = {}
    for name, value in variables.items():
        if name.startswith("__"):
            continue
        if isinstance(value, dict):
            if depth < 3:
                out.update(numeric_variables(value, f"{prefix}{name}.", depth + 1))
            continue
        try:
            array = np.asarray(value)
        except (ValueError, TypeError):  # a cell array of unlike parts
            continue
        if array.dtype.kind in "fiu":
            out[f"{prefix}{name}"] = array
    return out


def main(argv: list[str] | None = None) -> int:
    """Read a ``.mat`` file on stdin, write its numeric variables to stdout as ``.npz``.

    Parameters
    ----------
    argv : list of str, optional
        ``[limit]``: the most numbers the file's variables may hold (default: the
        process's own arguments).

    Returns
    -------
    int
        The exit status: 0 read, :data:`UNREADABLE`, :data:`TOO_LARGE`.
    """
    import numpy as np
    from scipy.io import loadmat, whosmat

    limit = int((argv if argv is not None else sys.argv[1:])[0])
    resource.setrlimit(resource.RLIMIT_AS, (MEMORY_BYTES, MEMORY_BYTES))
    data = sys.stdin.buffer.read()
    try:
        listed = whosmat(io.BytesIO(data))
        if sum(int(np.prod(shape)) for _, shape, _ in listed) > limit:
            return TOO_LARGE
        variables = loadmat(io.BytesIO(data), squeeze_me=True, simplify_cells=True)
        numbers = numeric_variables(variables)
    except Exception:  # scipy raises several kinds for a damaged file
        return UNREADABLE
    out = io.BytesIO()
    np.savez(out, **numbers)
    sys.stdout.buffer.write(out.getvalue())
    return 0


if __name__ == "__main__":
    sys.exit(main())
