"""Shared by the tests that run the repository's Snakefile for real: paths and the command line."""
import subprocess
import sys
from pathlib import Path

import yaml

REPO = Path(__file__).resolve().parents[1]
TEST_CONFIG_FILE = REPO / "tests" / "config.yaml"
TEST_CONFIG = yaml.safe_load(TEST_CONFIG_FILE.read_text())
SNAKEMAKE = Path(sys.executable).with_name("snakemake")
RERUN = Path(sys.executable).with_name("rerun")


def snakemake_command(workdir, *targets, configfile=TEST_CONFIG_FILE):
    """Command line that runs the repository's Snakefile on ``configfile`` with ``workdir`` as working directory."""
    return [str(SNAKEMAKE), "--snakefile", str(REPO / "Snakefile"), "--directory", str(workdir),
            "--configfile", str(configfile), "--cores", "2", *targets]


def run_snakemake(workdir, *targets, configfile=TEST_CONFIG_FILE, timeout=900):
    """Run :func:`snakemake_command` and return the completed process (output captured as text)."""
    return subprocess.run(snakemake_command(workdir, *targets, configfile=configfile), capture_output=True,
                          text=True, timeout=timeout)

