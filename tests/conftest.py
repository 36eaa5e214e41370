"""Shared fixtures: paths to the read-only data mirror beside the repository."""
from pathlib import Path

import pytest
import trimesh

REPO = Path(__file__).resolve().parents[1]
SHARED_DATA = REPO.parent / "shared" / "data"


@pytest.fixture(scope="session")
def bunny_res4():
    """Stanford's bunny_res4 (453 vertices, 948 faces) from the mirror, as shipped."""
    return trimesh.load(SHARED_DATA / "stanford" / "bunny_res4.ply", process=False)
