# `make run` runs the full sweep and its report; `make test` runs the test suite (CI: .ci/run); `make check` runs
# the fast tests (no Snakemake, Slurm or browser; about a minute); `make docs` builds the documentation site. All
# create .venv and install the project when needed; only `make test` installs Debian packages.
PYTHON ?= python3
VENV := .venv
STAMP := $(VENV)/.installed
CORES ?= 2

.PHONY: run test check docs bench profile clean

$(STAMP): pyproject.toml
	test -x $(VENV)/bin/python || $(PYTHON) -m venv $(VENV)
	$(VENV)/bin/python -m pip install --quiet --upgrade pip
	$(VENV)/bin/python -m pip install --quiet -e '.[all,test,slurm,docs]'
	touch $(STAMP)

run: $(STAMP)
	$(VENV)/bin/snakemake --cores $(CORES)

test: $(STAMP)  # on $(CORES) pytest-xdist workers, each test module on one (tests/conftest.py)
	bash tests/system_packages.sh
	$(VENV)/bin/python -m pytest -q -n $(CORES) --dist loadscope

check: $(STAMP)
	$(VENV)/bin/python -m pytest -q -n $(CORES) --dist loadscope -m "not slow"

docs: $(STAMP)  # the site into docs/_build/html, running the gallery's examples on one thread; warnings are errors
	OMP_NUM_THREADS=1 OPENBLAS_NUM_THREADS=1 MKL_NUM_THREADS=1 \
	$(VENV)/bin/sphinx-build -W --keep-going -b html docs docs/_build/html

bench: $(STAMP)
	$(VENV)/bin/python benchmarks/em_speed.py
	$(VENV)/bin/python benchmarks/registration_speed.py
	$(VENV)/bin/python benchmarks/cpd_speed.py

profile: $(STAMP)  # cold sweep of a clone of HEAD in sweep units, per-rule job times (docs/benchmarks/sweep.md)
	$(VENV)/bin/python benchmarks/sweep_profile.py --cores $(CORES)

clean:
	rm -rf results .snakemake docs/_build docs/api/generated docs/auto_examples
