"""Before and after, alternated: run one benchmark on an earlier commit and on this
checkout, one after the other, PAIRS times (a shared machine's speed drifts; alternating
keeps the two sides in the same conditions).

    .venv/bin/python bench/alternate.py REV PAIRS OUT -- bench/load_test.py --students 60

The earlier side runs from a worktree of REV, *as its working directory*: the benchmarks
start their servers with ``python -m app.cli.main`` and seed with ``python -c``, and both
put the working directory first on the import path -- a worktree merely put on
``PYTHONPATH`` from this checkout serves this checkout's code on both sides.  Outputs go to
OUT/before-N.txt and OUT/after-N.txt.
"""

from __future__ import annotations

import argparse
import os
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def worktree(rev: str) -> Path:
    """A detached worktree of ``rev`` in the temporary folder (made once, then reused)."""
    commit = subprocess.run(
        ["git", "rev-parse", "--short", rev], cwd=ROOT, check=True, capture_output=True, text=True
    ).stdout.strip()
    folder = Path(os.environ.get("TMPDIR", "/tmp")) / f"gyrolab-before-{commit}"
    if not folder.exists():
        subprocess.run(
            ["git", "worktree", "add", "--detach", "-f", str(folder), commit],
            cwd=ROOT,
            check=True,
            capture_output=True,
        )
    return folder


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("rev", help="the earlier commit")
    parser.add_argument("pairs", type=int)
    parser.add_argument("out", type=Path, help="a folder for the outputs")
    parser.add_argument("command", nargs=argparse.REMAINDER, help="-- SCRIPT [ARGS...]")
    args = parser.parse_args()
    command = args.command[1:] if args.command[:1] == ["--"] else args.command
    if not command:
        parser.error("give the benchmark to run after --")
    args.out.mkdir(parents=True, exist_ok=True)
    sides = {"before": worktree(args.rev), "after": ROOT}
    env = {name: value for name, value in os.environ.items() if name != "PYTHONPATH"}
    for pair in range(1, args.pairs + 1):
        for side, folder in sides.items():
            target = args.out / f"{side}-{pair}.txt"
            with target.open("w") as output:
                subprocess.run(
                    [sys.executable, *command], cwd=folder, env=env, stdout=output,
                    stderr=subprocess.STDOUT, check=False,
                )  # fmt: skip
            print(f"{side} {pair}: {target}", flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
