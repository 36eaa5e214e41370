"""Shared fixtures: paths to the read-only data mirror beside the repository, and the session's one run of the
workflow's stages on tests/config.yaml. How the tests are spread over pytest-xdist's workers (`make test` runs two
with ``--dist loadscope``)."""
from pathlib import Path

import pytest
import trimesh

from tests.workflow import STAGES, run_snakemake

REPO = Path(__file__).resolve().parents[1]
SHARED_DATA = REPO.parent / "shared" / "data"
WORKFLOW_MODULES = ("tests/test_checks.py", "tests/test_data_workflow.py", "tests/test_fit_workflow.py",
                    "tests/test_odometry_workflow.py", "tests/test_registration_workflow.py")
"""The modules whose tests read the session's workflow run (``workflow_run``): one worker runs them all, so that the
run is made once."""
LONG_FIRST = ("workflow_run", "tests/test_slurm.py", "tests/test_odometry_rotation.py", "tests/test_odometry_cli.py",
              "tests/test_cli.py", "tests/test_docs.py", "tests/test_report.py", "tests/test_packaging.py")
"""The groups of tests (`group_of`) that take longest, each a minute or more of one worker: handed out first, so
that no worker ends the session on one of them while the other has nothing left."""


def group_of(nodeid):
    """The group of the test ``nodeid`` that one worker runs whole: its module, or "workflow_run" for the modules
    that read the session's workflow run (`WORKFLOW_MODULES`)."""
    module = nodeid.split("::")[0]
    return "workflow_run" if module in WORKFLOW_MODULES else module


def pytest_collection_modifyitems(config, items):
    """Check that every test of the workflow run is in `WORKFLOW_MODULES`, and put the longest groups first."""
    strays = sorted({item.nodeid.split("::")[0] for item in items if "workflow_run" in item.fixturenames
                     and group_of(item.nodeid) != "workflow_run"})
    if strays:
        raise pytest.UsageError(f"tests/conftest.py: add {', '.join(strays)} to WORKFLOW_MODULES (they read the "
                                "session's workflow run)")
    rank = {group: place for place, group in enumerate(LONG_FIRST)}
    items.sort(key=lambda item: rank.get(group_of(item.nodeid), len(rank)))


@pytest.hookimpl(optionalhook=True)
def pytest_xdist_make_scheduler(config, log):
    """``--dist loadscope`` by `group_of`: a module's tests on one worker, so that its module-scoped fixtures are
    built once, the workflow modules together, and the groups handed out in collection order (longest first)."""
    if config.getvalue("dist") != "loadscope":
        return None
    from xdist.scheduler import LoadScopeScheduling

    class GroupScheduling(LoadScopeScheduling):
        def _split_scope(self, nodeid):
            return group_of(nodeid)

    config.option.loadscopereorder = False  # keep the collection's order, not the largest groups by test count
    return GroupScheduling(config, log)


@pytest.fixture(scope="session")
def bunny_res4():
    """Stanford's bunny_res4 (453 vertices, 948 faces) from the mirror, as shipped."""
    return trimesh.load(SHARED_DATA / "stanford" / "bunny_res4.ply", process=False)


@pytest.fixture(scope="session")
def workflow_run(tmp_path_factory):
    """Working directory of one uninterrupted `snakemake data fits registration odometry checks` on
    tests/config.yaml, run once per session: every test of a stage's outputs reads it (`WORKFLOW_MODULES`). It is
    not to be changed; a test that deletes, interrupts or reruns works on a copy (``tests.workflow.copy_run``) or in
    a directory of its own."""
    workdir = tmp_path_factory.mktemp("workflow")
    run = run_snakemake(workdir, *STAGES, timeout=1800)
    assert run.returncode == 0, run.stderr[-3000:]
    return workdir
