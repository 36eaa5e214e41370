"""The rule files as Snakemake's catalogue expects: `snakemake --lint` asks for nothing but a conda environment or
container per rule (answered in docs/user_guide/workflow.md: software is deployed by pip into .venv), `snakefmt --check`
passes."""
import re
import subprocess
import sys
from pathlib import Path

import pytest

from tests.workflow import REPO, SNAKEMAKE

CONDA_LINT = "Specify a conda environment or container for each rule."


@pytest.mark.slow  # runs Snakemake (7 s): make check runs none
def test_lint_asks_only_for_conda_environments(tmp_path):
    command = [str(SNAKEMAKE), "--snakefile", str(REPO / "Snakefile"), "--directory", str(tmp_path),
               "--configfile", str(REPO / "config.yaml"), "--lint"]
    run = subprocess.run(command, capture_output=True, text=True, timeout=120, cwd=REPO)
    output = run.stdout + run.stderr
    lints = re.findall(r"^\s+\* (.*):$", output, flags=re.MULTILINE)
    assert lints, output[-3000:]  # the conda request is expected: an empty list means lint did not run
    assert set(lints) == {CONDA_LINT}, output[-3000:]
    assert "Lints for snakefile" not in output, output[-3000:]


def test_rule_files_are_formatted():
    snakefmt = Path(sys.executable).with_name("snakefmt")
    run = subprocess.run([str(snakefmt), "--check", "Snakefile", "workflow/"], capture_output=True, text=True,
                         timeout=120, cwd=REPO)
    assert run.returncode == 0, run.stderr[-3000:] + "\n(format with: snakefmt Snakefile workflow/)"
