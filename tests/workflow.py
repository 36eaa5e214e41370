"""Shared by the tests that run the repository's Snakefile for real: paths, the command line, table checksums."""
import hashlib
import subprocess
import sys
from pathlib import Path

import pytest
import yaml

REPO = Path(__file__).resolve().parents[1]
TEST_CONFIG_FILE = REPO / "tests" / "config.yaml"
TEST_CONFIG = yaml.safe_load(TEST_CONFIG_FILE.read_text())
SNAKEMAKE = Path(sys.executable).with_name("snakemake")
RERUN = Path(sys.executable).with_name("rerun")
# sha256 of the tables tests/config.yaml gives, recorded at main 38794a7 before the sweep's overhead was cut (issue 15;
# odometry.csv at c343ddf, before the job server; registration.csv again when the scaled protocol's mixtures got their
# scaled covariance floor, which moves the bunny's by a factor 1.00012; odometry.csv again when the odometry's per-frame
# schedule became a choice, the sweep's "fast", with a schedule column; and when the sweep's schedule became "overlap",
# with the EM start's seeding written in numpy, again when its cut became exact and iterated, and when the registration
# before the cut rounds stopped at their tolerance: the ICP row is unchanged; registration.csv and odometry.csv again
# when ICP kept its points coordinate-major: the ICP rows moved in their last 2-3 digits, the same iterations): changes
# to how jobs run must leave every number as it was. They hold for this machine's numpy and OpenBLAS; a platform whose
# arithmetic differs in the last bits changes them, and then they are updated on purpose: all three again on an AMD
# EPYC (numpy 2.4, OpenBLAS 0.3.31, Haswell kernels), whose last bits differ from the machine before (the code before
# the package's three floors gave 09110829…, 66eeeddc… and 111907e7… there), and likelihood.csv and odometry.csv
# once more when scoring padded its products to whole BLAS tiles (one likelihood cell and the odometry's cuts moved in
# their last digit; registration.csv unchanged); odometry.csv again when Gauss-Newton's D2D and the frames' screened
# E-step became numba kernels (issue 40: the two GMM rows' ATE moved by 1.2e-16 and 1.7e-16 m, in their 14th digit;
# the ICP row unchanged; the table before: 7947d2a3…); and when a screened fit's E-step and M-step sums became one
# kernel (issue 40: gmm-pixels' ATE moved by 1.2e-14 m, gmm-points' by -1.8e-15 m, in their 12th-13th digit; RPE and
# the ICP row unchanged; the table before: 9726e863…).
# Those were all on one machine at a time. A machine with AVX-512 (OpenBLAS's SkylakeX kernels, numpy's AVX-512 loops)
# rounds differently from the Haswell-kernel one before and gives other bytes for all three at the same code, so the
# hashes are kept per platform (:func:`platform`), and a platform without a recorded table skips its check, naming
# the hash it got. On SkylakeX: recorded at 715a12d for likelihood.csv and odometry.csv, and registration.csv when
# P2D's BFGS moved onto the numba kernels (issue 40; Haswell's before it, 66eeeddc…, is not recorded since).
TABLE_SHA256 = {
    "OpenBLAS Haswell, numpy AVX2": {
        "likelihood.csv": "eaf451d4edad41805db91597b47bc5b473f710303ce5ef829bc5f43a3d57f153",
        "odometry.csv": "cc2ec3995f5a06b621e41e4ab3f903cdef1999f15aaeb6ec7a4228ed1a5b2681",
    },
    "OpenBLAS SkylakeX, numpy AVX512F": {
        "likelihood.csv": "3d0c51c9731daea1632da6de217800532df4a3286b6f5e52acb14642877f2078",
        "registration.csv": "c835d367b3c5e2ce0681fc372df3a33cfd8e7bb572077e8d5cb589c4d62ca9d7",
        "odometry.csv": "0faf4a7acbac6779d5ba6d16c6f5613b6fea6c9efd3e076dbf1c2ca1c45d139d",
    },
}


def platform():
    """What the tables' last bits depend on: OpenBLAS's kernels and the widest vector loops numpy runs here."""
    from numpy._core._multiarray_umath import __cpu_features__
    from threadpoolctl import threadpool_info

    kernels = {info.get("architecture") for info in threadpool_info() if info["internal_api"] == "openblas"}
    vector = next((name for name in ("AVX512F", "AVX2") if __cpu_features__.get(name)), "baseline")
    return f"OpenBLAS {', '.join(sorted(map(str, kernels))) or 'absent'}, numpy {vector}"


def assert_recorded_table(path):
    """The table at ``path`` has the bytes recorded for this platform; skipped where none are recorded."""
    name, here, got = Path(path).name, platform(), sha256(path)
    recorded = TABLE_SHA256.get(here, {}).get(name)
    if recorded is None:
        pytest.skip(f"no {name} recorded for {here}; its sha256 here: {got}")
    assert got == recorded, f"{name} on {here}: sha256 {got}, recorded {recorded}"


def snakemake_command(workdir, *targets, configfile=TEST_CONFIG_FILE):
    """Command line that runs the repository's Snakefile on ``configfile`` with ``workdir`` as working directory."""
    return [str(SNAKEMAKE), "--snakefile", str(REPO / "Snakefile"), "--directory", str(workdir),
            "--configfile", str(configfile), "--cores", "2", *targets]


def run_snakemake(workdir, *targets, configfile=TEST_CONFIG_FILE, timeout=900):
    """Run :func:`snakemake_command` and return the completed process (output captured as text)."""
    return subprocess.run(snakemake_command(workdir, *targets, configfile=configfile), capture_output=True,
                          text=True, timeout=timeout)


def sha256(path):
    """Hex sha256 of a file's bytes."""
    return hashlib.sha256(Path(path).read_bytes()).hexdigest()
