"""Shared by the tests that run the repository's Snakefile for real: paths, the command line, and the config check
that the Snakefile makes first (common.smk's `validate`), run in this process."""
import copy
import shutil
import subprocess
import sys
from pathlib import Path

import yaml

REPO = Path(__file__).resolve().parents[1]
TEST_CONFIG_FILE = REPO / "tests" / "config.yaml"
TEST_CONFIG = yaml.safe_load(TEST_CONFIG_FILE.read_text())
SCHEMA = REPO / "workflow" / "schemas" / "config.schema.yaml"
SNAKEMAKE = Path(sys.executable).with_name("snakemake")
RERUN = Path(sys.executable).with_name("rerun")
STAGES = ("data", "fits", "registration", "odometry", "checks")
"""The targets of the session's one workflow run (conftest.py's ``workflow_run``): every stage but the report."""


def snakemake_command(workdir, *targets, configfile=TEST_CONFIG_FILE):
    """Command line that runs the repository's Snakefile on ``configfile`` with ``workdir`` as working directory."""
    return [str(SNAKEMAKE), "--snakefile", str(REPO / "Snakefile"), "--directory", str(workdir),
            "--configfile", str(configfile), "--cores", "2", *targets]


def run_snakemake(workdir, *targets, configfile=TEST_CONFIG_FILE, timeout=900):
    """Run :func:`snakemake_command` and return the completed process (output captured as text)."""
    return subprocess.run(snakemake_command(workdir, *targets, configfile=configfile), capture_output=True,
                          text=True, timeout=timeout)


def copy_run(workdir, target):
    """Copy a working directory of a finished run (results and Snakemake's records, mtimes kept) to ``target``, for
    a test that changes it; returns ``target``."""
    shutil.copytree(workdir, target, symlinks=True)
    return target


def config_error(config):
    """The error that the Snakefile's config validation (``validate`` against the schema, common.smk's first
    statement) raises on ``config``, as text; "" when the config passes.

    Parameters
    ----------
    config : dict
        A config as ``--configfile`` would give it (left unchanged; validation fills defaults into a copy).

    Returns
    -------
    str
    """
    from snakemake.exceptions import WorkflowError
    from snakemake.utils import validate

    try:
        validate(copy.deepcopy(config), schema=str(SCHEMA))
    except WorkflowError as error:
        return str(error)
    return ""
