#!/usr/bin/env python3
"""Executes a notebook headless with nbclient, in its own directory, on the interpreter's own
kernel; any cell that raises fails (exit 1). tests/CMakeLists.txt runs it on
examples/notebooks/tuning.ipynb with the build's ftctune package on PYTHONPATH."""
import os
import pathlib
import sys
import time

import nbclient
import nbformat

# The kernel's debugger warns on stderr about frozen modules otherwise.
os.environ.setdefault("PYDEVD_DISABLE_FILE_VALIDATION", "1")
path = pathlib.Path(sys.argv[1]).resolve()
nb = nbformat.read(path, as_version=4)
start = time.monotonic()
client = nbclient.NotebookClient(nb, timeout=120, kernel_name="python3",
                                 resources={"metadata": {"path": str(path.parent)}})
try:
    client.execute()
except nbclient.exceptions.CellExecutionError as e:
    print(e, file=sys.stderr)
    sys.exit(1)
cells = sum(1 for c in nb.cells if c.cell_type == "code")
print(f"{path.name}: {cells} code cells ran in {time.monotonic() - start:.1f} s")
