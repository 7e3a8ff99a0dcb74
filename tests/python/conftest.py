"""What the pytest suite of `import driftlab` shares: where the sources and the driftlab program
are, and one small run of the sweep tests' scenario."""

import os

import pytest

import driftlab

SOURCE = os.environ.get("DRIFTLAB_SOURCE_DIR",
                        os.path.normpath(os.path.join(os.path.dirname(__file__), "..", "..")))
CLI = os.environ.get("DRIFTLAB", os.path.join(SOURCE, "build", "bin", "driftlab"))
TINY = os.path.join(SOURCE, "tests", "data", "sweeps", "tiny_base.yaml")
TINY_GRID = os.path.join(SOURCE, "tests", "data", "sweeps", "tiny_grid.yaml")


@pytest.fixture(scope="session")
def tiny_run(tmp_path_factory):
    """The tiny scenario run with sparse and sparse_kf: (its folder, its run record)."""
    out = tmp_path_factory.mktemp("run") / "tiny"
    scenario = driftlab.Scenario.load(TINY, set={"pipeline.vo": ["sparse", "sparse_kf"]})
    return out, driftlab.run(scenario, out)
