"""docs/tutorial.ipynb is stored with its outputs (so that a code host shows its figures)
and runs from top to bottom in a fresh kernel (nbclient).

``make notebook`` runs this file as a script: it executes the notebook with
:func:`run_notebook` (the same run the slow test makes) and stores it with its outputs,
stamped with the hash of the code it ran (:func:`code_hash`), so that a test can tell stored
outputs that no longer belong to the code. Nothing is written if a cell fails.
"""

from __future__ import annotations

import hashlib
import re
import sys
import time
from pathlib import Path

import pytest

from tests.helpers import needs_fma

NOTEBOOK = Path(__file__).resolve().parents[2] / "docs" / "tutorial.ipynb"
#: The stored notebook's size limit [bytes]: its PNGs are embedded.
MAX_BYTES = 1_500_000
#: A code cell draws if it calls one of atlas's figure functions, the notebook's own
#: ``side_by_side`` or pyplot's ``subplots``; it prints if it calls ``print``.
DRAWS = re.compile(r"\b(basin_map|trap_time_map|boundary_distance_map|fraction_curves|"
                   r"basin_stability|side_by_side|plt\.subplots)\(")
PRINTS = re.compile(r"\bprint\(")
#: Where the hash of the code cells that produced the stored outputs is kept.
STAMP = "atlas_outputs_of"


def code_hash(nb) -> str:
    """SHA-256 of the notebook's code cells' sources, in order."""
    code = "\n\0".join(c.source for c in nb.cells if c.cell_type == "code")
    return hashlib.sha256(code.encode()).hexdigest()


def run_notebook(nb):
    """Execute ``nb`` (in place) in a fresh ``python3`` kernel whose working directory is
    docs/, as a reader would; no per-cell timing metadata (it changes every run). Raises
    nbclient's CellExecutionError (the cell and its traceback) on any error."""
    import nbclient

    nbclient.NotebookClient(nb, timeout=300, kernel_name="python3", record_timing=False,
                            resources={"metadata": {"path": str(NOTEBOOK.parent)}}).execute()
    return nb


def _outputs(cell, kind: str) -> list:
    """The outputs of ``cell`` of ``kind``: "image" (PNG), "stdout", "stderr" or "error"."""
    if kind == "image":
        return [o for o in cell.outputs if "image/png" in o.get("data", {})]
    if kind in ("stdout", "stderr"):
        return [o for o in cell.outputs if o.output_type == "stream" and o.name == kind]
    return [o for o in cell.outputs if o.output_type == kind]


def _stored():
    import nbformat

    nb = nbformat.read(NOTEBOOK, as_version=4)
    nbformat.validate(nb)
    return nb


def test_every_drawing_and_printing_cell_has_its_outputs_stored():
    nb = _stored()
    code = [c for c in nb.cells if c.cell_type == "code"]
    draws = [c for c in code if DRAWS.search(c.source)]
    prints = [c for c in code if PRINTS.search(c.source)]
    assert len(draws) >= 8 and len(prints) >= 5  # the tour: maps, curves, orbit, torque
    assert all(_outputs(c, "image") for c in draws), [
        c.source.splitlines()[0] for c in draws if not _outputs(c, "image")]
    assert all(_outputs(c, "stdout") for c in prints), [
        c.source.splitlines()[0] for c in prints if not _outputs(c, "stdout")]
    # no error, and no warning either (a warning on stderr is a figure or number to fix)
    assert not [c.source.splitlines()[0] for c in code
                if _outputs(c, "error") or _outputs(c, "stderr")]
    # run from top to bottom in one kernel, not cell by cell out of order
    assert [c.execution_count for c in code] == list(range(1, len(code) + 1))


def test_stored_outputs_belong_to_the_code_and_are_small():
    nb = _stored()
    assert nb.metadata.get(STAMP) == code_hash(nb), (
        "docs/tutorial.ipynb: its code changed since its outputs were stored; `make notebook`")
    assert NOTEBOOK.stat().st_size < MAX_BYTES
    # nothing that changes from run to run: no timestamps
    assert not [c for c in nb.cells if "execution" in c.get("metadata", {})]


def test_the_point_theta0_0_is_on_the_grid():
    """The "one point" cell selects θ0 = 0 by its exact label (and asserts it): its stored
    printout names that point, not a neighbour of it."""
    text = "".join(o.text for c in _stored().cells if c.cell_type == "code"
                   for o in _outputs(c, "stdout"))
    assert "θ0 = 0.0 rad, θ̇0 = 2.5 rad/s: k = " in text


@pytest.fixture(scope="module")
def rerun():
    """The stored notebook run again from top to bottom in a fresh kernel (once for the
    module's tests); raises CellExecutionError with the cell on any error."""
    pytest.importorskip("nbclient")
    return run_notebook(_stored())


@pytest.mark.slow
def test_tutorial_runs_and_gives_the_stored_kinds_of_output(rerun):
    stored = _stored()
    code = [c for c in rerun.cells if c.cell_type == "code"]
    kinds = ("image", "stdout", "stderr", "error")
    assert [[len(_outputs(c, k)) for k in kinds] for c in code] == [
        [len(_outputs(c, k)) for k in kinds] for c in stored.cells if c.cell_type == "code"]
    text = "".join(o.text for c in code for o in _outputs(c, "stdout"))
    assert "wells in the window: [0, 1]" in text and "boundary distance" in text
    assert "rest states θ = " in text and "k = [-1, 0, 1]" in text


def _seen(output) -> list:
    """What a reader sees of one output: its printed text, its text/plain and the pixels of
    its PNG (decoded: the PNG's bytes also hold matplotlib's version)."""
    import base64
    import io

    import numpy as np
    from PIL import Image

    data = output.get("data", {})
    seen = [output.output_type, output.get("name"), output.get("text"), data.get("text/plain")]
    if "image/png" in data:
        image = Image.open(io.BytesIO(base64.b64decode(data["image/png"])))
        seen.append(np.asarray(image).tobytes() + repr(image.size).encode())
    return seen


@pytest.mark.slow
@needs_fma
def test_the_stored_outputs_are_what_the_current_library_gives(rerun):
    """Every stored output is the current library's, not only the stored code's: the
    printed numbers, the tables and every figure's pixels of a fresh run equal the stored
    ones exactly (a change of atlas that moves a number or a pixel fails here, until `make
    notebook` stores the new outputs). Exact, so on a host like the one that stored them
    (fused multiply-add: a·b + c rounded once; elsewhere last digits may differ)."""
    stored = [c for c in _stored().cells if c.cell_type == "code"]
    fresh = [c for c in rerun.cells if c.cell_type == "code"]
    differ = [c.source.splitlines()[0] for c, d in zip(stored, fresh)
              if [_seen(o) for o in c.outputs] != [_seen(o) for o in d.outputs]]
    assert not differ, ("docs/tutorial.ipynb: outputs differ from the current library's "
                        f"in the cells starting {differ}; `make notebook`")


def main() -> int:
    """``make notebook``: run docs/tutorial.ipynb and store it with its outputs."""
    start = time.perf_counter()
    nb = run_notebook(_stored())
    nb.metadata[STAMP] = code_hash(nb)
    import nbformat

    nbformat.validate(nb)
    nbformat.write(nb, NOTEBOOK)
    figures = sum(len(_outputs(c, "image")) for c in nb.cells if c.cell_type == "code")
    print(f"wrote {NOTEBOOK} ({NOTEBOOK.stat().st_size / 1e3:.0f} kB, {figures} figures) "
          f"in {time.perf_counter() - start:.0f} s")
    return 0


if __name__ == "__main__":
    sys.exit(main())
