"""The sweep profile's computation and its floor (benchmarks/sweep_profile.py) on a hand-made results tree."""
import sys
from pathlib import Path

import pytest

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "benchmarks"))

from sweep_profile import floor_line, job_times  # noqa: E402


def _write(path, text):
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(text)


@pytest.fixture
def results(tmp_path):
    """Four jobs: a fit (seeds 0.5 + 1.5 s), an odometry run (frames 3 + 5 s of CPU, one frame untimed), a timing
    check (repeats 4 + 6 s) and the report (no timing table); job walls 3, 12, 11 and 2 s."""
    bench = tmp_path / "benchmarks"
    for path, wall in [("fit/bunny/res4-exact/textbook/k6-kmeans.tsv", 3), ("odometry_run/seq/icp.tsv", 12),
                       ("check_timing/decimation.tsv", 11), ("report.tsv", 2)]:
        _write(bench / path, f"s\th:m:s\tmax_rss\n{wall}\t0:00:0{wall % 10}\t1\n")
    _write(tmp_path / "fits/bunny/res4-exact/textbook/k6-kmeans/seconds.csv", "seed,fit_seconds\n0,0.5\n1,1.5\n")
    _write(tmp_path / "odometry/seq/icp/seconds.csv", "frame,cpu_seconds\n0,3\n1,\n2,5\n")
    _write(tmp_path / "checks/timing/decimation.csv", "setting,repeat,seconds\nquadric,0,4\nclustering,0,6\n")
    return tmp_path


def test_job_times_read_each_rules_own_timing_table(results):
    jobs = job_times(results)
    assert jobs == {"fit": [(3.0, 2.0)], "odometry_run": [(12.0, 8.0)], "check_timing": [(11.0, 10.0)],
                    "report": [(2.0, None)]}


def test_the_floor_is_the_computation_spread_over_the_cores(results):
    line = floor_line(job_times(results), cores=2, yardstick=0.5)
    assert "20 of 28 s of job time" in line
    assert "10 s, **20.0 sweep units**" in line
    assert "units" not in floor_line(job_times(results), cores=2)
