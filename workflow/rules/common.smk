# Config validation and helpers shared by every rule file.
from snakemake.utils import validate


validate(config, schema="../schemas/config.schema.yaml")

RESULTS = config.get("results", "results")


def get_final_output():
    """Every target of `rule all`: the outputs of each stage."""
    return [*rules.data.input, *rules.fits.input, *rules.registration.input]
