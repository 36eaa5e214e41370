#!/usr/bin/env bash
# Debian packages some tests drive for real: headless Chromium (tests/test_report.py renders the report) and a
# single-node Slurm (tests/test_slurm.py). Installed when missing and apt-get can run (as root); otherwise those
# tests are skipped with a reason. In CI (CI=true) a failed install fails the run.
set -uo pipefail
packages=(chromium slurmctld slurmd slurm-client munge)
missing=()
for package in "${packages[@]}"; do
    dpkg-query -W -f='${Status}' "$package" 2>/dev/null | grep -q "install ok installed" || missing+=("$package")
done
[ ${#missing[@]} -eq 0 ] && exit 0
if [ "$(id -u)" -eq 0 ] && command -v apt-get >/dev/null \
    && apt-get update -qq && DEBIAN_FRONTEND=noninteractive apt-get install -y -qq "${missing[@]}" >/dev/null; then
    echo "installed ${missing[*]}"
elif [ "${CI:-}" = "true" ]; then
    echo "error: could not install ${missing[*]} with apt-get; the Chromium and Slurm tests need them" >&2
    exit 1
else
    echo "warning: could not install ${missing[*]}; the tests that need them will be skipped" >&2
fi
