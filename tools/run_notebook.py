#!/usr/bin/env python3
"""Execute a notebook from the repository's root, as CI does (nbclient, the python3 kernel), and
fail on the first cell that raises. Prints each code cell's wall time. With `-o OUT.ipynb`, also
writes the executed notebook (outputs included) there.

    python3 tools/run_notebook.py notebooks/lecture.ipynb [-o executed.ipynb]
"""

import argparse
import sys
import time
from pathlib import Path

import nbformat
from nbclient import NotebookClient
from nbclient.exceptions import CellExecutionError

ROOT = Path(__file__).resolve().parents[1]


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("notebook", type=Path)
    ap.add_argument("-o", "--output", type=Path)
    ap.add_argument("--timeout", type=int, default=600, help="seconds per cell")
    args = ap.parse_args()
    nb = nbformat.read(args.notebook, as_version=4)
    client = NotebookClient(nb, timeout=args.timeout, kernel_name="python3", resources={"metadata": {"path": str(ROOT)}})
    start = time.monotonic()
    with client.setup_kernel():
        for index, cell in enumerate(nb.cells):
            if cell.cell_type != "code":
                continue
            t = time.monotonic()
            try:
                client.execute_cell(cell, index)
            except CellExecutionError as e:
                print(f"{args.notebook}: cell {index} failed:\n{e}", file=sys.stderr)
                return 1
            print(f"cell {index:2d}: {time.monotonic() - t:6.1f} s")
    print(f"{args.notebook}: ran in {time.monotonic() - start:.1f} s")
    if args.output:
        nbformat.write(nb, args.output)
    return 0


if __name__ == "__main__":
    sys.exit(main())
