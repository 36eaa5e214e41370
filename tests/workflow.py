"""Shared by the tests that run the repository's Snakefile for real: paths, the command line, table checksums."""
import hashlib
import subprocess
import sys
from pathlib import Path

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
TABLE_SHA256 = {
    "likelihood.csv": "eaf451d4edad41805db91597b47bc5b473f710303ce5ef829bc5f43a3d57f153",
    "registration.csv": "66eeeddc28e207085949fdc1b8b33087740e3d0affe605a1d1ca6f53af577970",
    "odometry.csv": "cc2ec3995f5a06b621e41e4ab3f903cdef1999f15aaeb6ec7a4228ed1a5b2681",
}


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
