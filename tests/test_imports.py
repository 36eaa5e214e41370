"""The command line starts without its heavy dependencies: they are imported by the commands that use them."""
import subprocess
import sys

import dgmm

HEAVY = ("sklearn", "trimesh", "rerun", "mcap", "scipy.optimize", "matplotlib")


def test_help_imports_no_heavy_dependency():
    probe = ("import sys, dgmm.cli\n"
             "try:\n    dgmm.cli.main(['--help'])\nexcept SystemExit:\n    pass\n"
             f"print(sorted(name for name in {HEAVY!r} if name in sys.modules))")
    run = subprocess.run([sys.executable, "-c", probe], capture_output=True, text=True, check=True)
    assert run.stdout.splitlines()[-1] == "[]"


def test_the_estimator_is_still_an_attribute_of_the_package():
    from dgmm import GaussianMixture
    from dgmm.mixture import GaussianMixture as defined

    assert GaussianMixture is defined is dgmm.GaussianMixture
    assert "GaussianMixture" in dgmm.__all__
