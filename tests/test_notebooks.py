"""Every notebook in notebooks/ runs top to bottom without error (``make test-all``)."""

from pathlib import Path

import pytest

NOTEBOOKS = sorted((Path(__file__).parents[1] / "notebooks").glob("*.ipynb"))


@pytest.mark.slow
@pytest.mark.parametrize("path", NOTEBOOKS, ids=[p.stem for p in NOTEBOOKS])
def test_notebook_executes(path, tmp_path):
    try:
        import nbclient
        import nbformat
    except ImportError as e:  # a fail that says what to do, not a skip
        pytest.fail(f"{e}: the notebook tests need the [notebooks] extra; run `make test-all` "
                    "(or pip install -e '.[dev,notebooks]')")  # fmt: skip

    nb = nbformat.read(path, as_version=4)
    client = nbclient.NotebookClient(
        nb, timeout=900, kernel_name="python3", resources={"metadata": {"path": str(tmp_path)}}
    )
    client.execute()  # raises CellExecutionError naming the failing cell
    errors = [o for c in nb.cells if c.cell_type == "code" for o in c.get("outputs", [])
              if o.get("output_type") == "error"]  # fmt: skip
    assert not errors
