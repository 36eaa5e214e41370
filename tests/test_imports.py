"""The command line starts without its heavy dependencies: they are imported by the commands that use them."""
import subprocess
import sys

import dgmm

HEAVY = ("numpy", "sklearn", "trimesh", "rerun", "mcap", "scipy", "matplotlib")


def test_help_imports_no_heavy_dependency():
    probe = ("import sys, dgmm.cli\n"
             "try:\n    dgmm.cli.main(['--help'])\nexcept SystemExit:\n    pass\n"
             f"print(sorted(name for name in {HEAVY!r} if name in sys.modules))")
    run = subprocess.run([sys.executable, "-c", probe], capture_output=True, text=True, check=True)
    assert run.stdout.splitlines()[-1] == "[]"


def test_the_lazy_attributes_are_the_package_s_classes():
    from dgmm import GaussianMixture, Primitives
    from dgmm.mixture import GaussianMixture as estimator
    from dgmm.primitives import Primitives as primitives

    assert GaussianMixture is estimator is dgmm.GaussianMixture
    assert Primitives is primitives is dgmm.Primitives
    assert {"GaussianMixture", "Primitives"} <= set(dgmm.__all__)
