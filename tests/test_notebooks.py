"""The notebooks of examples/: each runs from top to bottom, and each is committed without outputs.

They are executed here with nbclient, one test per notebook, rather than collected by a pytest
plugin such as nbmake, which collects ``.ipynb`` files only with its option on the command line
and examples/ among the paths (``addopts`` and ``testpaths`` changed for every run). As plain
tests they run in ``pytest -n 2`` from the repository root (xdist spreads them over both
workers), carry the ``slow`` marker like the suite's other long tests, and
use this interpreter's kernel: the kernel spec manager below sees only ipykernel's native kernel,
so a ``python3`` kernel installed elsewhere on the machine cannot run them in another environment.
"""

from __future__ import annotations

from pathlib import Path

import nbformat
import pytest

EXAMPLES = Path(__file__).resolve().parents[1] / "examples"
NOTEBOOKS = sorted(EXAMPLES.glob("*.ipynb"))
IDS = [path.stem for path in NOTEBOOKS]


def test_examples_hold_notebooks():
    assert len(NOTEBOOKS) >= 2, f"expected the teaching notebooks in {EXAMPLES}"


@pytest.mark.parametrize("path", NOTEBOOKS, ids=IDS)
def test_notebook_is_stripped(path):
    """No outputs, no execution counts, no saved widget state: the repository holds the source."""
    nb = nbformat.read(path, as_version=4)
    nbformat.validate(nb)
    code = [cell for cell in nb.cells if cell.cell_type == "code"]
    assert code, f"{path.name} has no code"
    for i, cell in enumerate(code):
        assert cell.outputs == [], f"{path.name}: code cell {i} has outputs"
        assert cell.execution_count is None, f"{path.name}: code cell {i} has an execution count"
    assert "widgets" not in nb.metadata, f"{path.name} holds saved widget state"


@pytest.mark.slow  # a kernel per notebook: about 3 s each once the numba kernels are cached
@pytest.mark.parametrize("path", NOTEBOOKS, ids=IDS)
def test_notebook_runs(path):
    """Every cell runs without an error, and nothing is written to stderr but emdm's own notice
    that it compiles its kernels (first use on a machine)."""
    from jupyter_client.kernelspec import KernelSpecManager
    from jupyter_client.manager import KernelManager
    from nbclient import NotebookClient

    nb = nbformat.read(path, as_version=4)
    specs = KernelSpecManager(kernel_dirs=[], ensure_native_kernel=True)  # this interpreter only
    km = KernelManager(kernel_name="python3", kernel_spec_manager=specs)
    client = NotebookClient(
        nb,
        km=km,
        timeout=600,  # per cell: the first use on a machine compiles the kernels (about a minute)
        resources={"metadata": {"path": str(EXAMPLES)}},  # run where the reader opens it
    )
    client.execute()
    for i, cell in enumerate(nb.cells):
        for out in cell.get("outputs", []):
            if out.output_type == "stream" and out.name == "stderr":
                lines = [line for line in out.text.splitlines() if not line.startswith("emdm:")]
                assert not lines, f"{path.name}, cell {i} wrote to stderr:\n{out.text}"
