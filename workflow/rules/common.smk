# Config validation, the paths every stage shares and the input functions of the rules (Snakemake's catalogue
# layout: the stage files hold rules only, the functions they call live here).
# Every rule that runs a script declares resources (mem_mb, runtime in minutes, cpus_per_task) for cluster
# schedulers (target rules run nothing and declare none): measured peaks (benchmarks/studies/job_resources.py,
# docs/user_guide/slurm.md) with about 2x memory and 15x time headroom.
import os

from snakemake.utils import validate

from dgmm.data import REGISTRY
from dgmm.odometry import odometry_runs
from dgmm.odometry.pixels import sequence_intrinsics
from dgmm.odometry.protocols import PROTOCOLS as ODOMETRY_PROTOCOLS, run_protocol
from dgmm.experiments.report import figure_names
from dgmm.experiments.sweep import parse_input, variants_for
from dgmm.experiments.trials import METHODS, NO_VARIANT, PROTOCOLS, method_variants, mixture_source

validate(config, schema="../schemas/config.schema.yaml")

RESULTS = config["results"]
DATA = config["data"]
DATA_DIR = f"{RESULTS}/data"
FIT = config["fit"]
REG = config["registration"]
ODO = config["odometry"]
ODO_DIR = f"{RESULTS}/odometry"
CHECKS = config["checks"]  # a section present runs its check (none by default)
SYNTHETIC_SEQUENCE = f"{ODO_DIR}/synthetic/sequence"
REPORT_DIR = config["report"]["dir"]
PICTURE_BUDGET = 1000  # Fig 5 shows the paper's 1000-primitive decimations and samples
# Rule priorities: of the jobs ready to run, Snakemake starts those of highest priority first. First the jobs every
# other waits on (the data stage), then the longest (odometry), then the others, roughly longest first, so that the
# sweep does not end with one core on a long job while the other idles (benchmarks/sweep_profile.py counts the idle
# core-seconds). Rules not listed have priority 0 (fits, the tables, the report).
PRIORITY = {
    "data": 40,  # data_mesh, data_eval, data_reduce: seconds each, and every fit and registration waits on them
    "odometry_synthetic": 30,  # a long job (44 s at 5ab1484), and the runs on the synthetic sequence wait on it
    "odometry_run": 20,
    "registration_gmm": 10,  # its method's chunks wait on it
    "registration_chunk": 5,
    "fig2": 5,
}


def get_final_output():
    """Every target of the workflow's default target: the outputs of each stage."""
    return [
        *rules.data.input,
        *rules.fits.input,
        *rules.registration.input,
        *rules.odometry.input,
        *rules.checks.input,
        *rules.report.output,
    ]


# Data stage


def data_dir(path):
    """A configured directory: "~" expanded, relative paths taken from the repository root (not the working dir)."""
    return os.path.normpath(os.path.join(workflow.basedir, os.path.expanduser(path)))


def data_targets():
    """Every file the data stage builds for the configured models."""
    targets = []
    for model in DATA["models"]:
        for mesh in REGISTRY[model]:
            targets += [f"{DATA_DIR}/{model}/{mesh}.ply", f"{DATA_DIR}/{model}/{mesh}_eval.ply"]
        targets += expand(
            f"{DATA_DIR}/{model}/{{method}}{{budget}}.ply", method=DATA["methods"], budget=DATA["budgets"]
        )
    return targets


# Fitting sweep


def fit_jobs():
    """(model, input, variant, K, init, max_iter) of every configured fit, each once; max_iter is the experiment's
    own when it sets one, else fit.max_iter."""
    jobs = set()
    for experiment in FIT["experiments"].values():
        max_iter = FIT["max_iter"] if experiment["max_iter"] is None else experiment["max_iter"]
        for model in experiment["models"]:
            for input_name in experiment["inputs"]:
                for variant in variants_for(input_name, FIT["variants"]):
                    for k in experiment["components"]:
                        for init in experiment["inits"]:
                            jobs.add((model, input_name, variant, k, init, max_iter))
    return sorted(jobs)


def fit_job_dir(model, input_name, variant, k, init, max_iter):
    """Folder of a fit job: fits/{model}/{input}/{variant}/k{K}-{init}, with -i{max_iter} appended when the job's
    iteration cap is not fit.max_iter (rule fit_capped)."""
    cap = "" if max_iter == FIT["max_iter"] else f"-i{max_iter}"
    return f"{RESULTS}/fits/{model}/{input_name}/{variant}/k{k}-{init}{cap}"


def fit_outputs(name):
    """File ``name`` of every configured fit job."""
    return [f"{fit_job_dir(*job)}/{name}" for job in fit_jobs()]


def fit_input(wildcards):
    """The fitted data file: the input's source mesh or its reduction."""
    return f"{DATA_DIR}/{wildcards.model}/{parse_input(wildcards.input)[0]}.ply"


def evaluation_set(wildcards):
    """Fig 3 inputs (made from res4) are scored on res4's evaluation set, all others on the full model's."""
    source = parse_input(wildcards.input)[0]
    mesh = source if source in ("full", "res4") else "full"
    return f"{DATA_DIR}/{wildcards.model}/{mesh}_eval.ply"


# Registration


def registration_experiments():
    """(model, mesh) -> (trials, methods, protocols) over every experiment; an experiment repeated on the same mesh
    takes the most trials, every method and every protocol (trials are the same for every experiment, see
    dgmm.experiments.trials)."""
    jobs = {}
    for experiment in REG["experiments"].values():
        for model in experiment["models"]:
            trials, methods, protocols = jobs.get((model, experiment["mesh"]), (0, [], []))
            methods = methods + [m for m in experiment["methods"] if m not in methods]
            protocols = protocols + [p for p in experiment["protocols"] if p not in protocols]
            jobs[model, experiment["mesh"]] = (max(trials, experiment["trials"]), methods, protocols)
    return jobs


REG_EXPERIMENTS = registration_experiments()


def chunk_range(wildcards):
    """[first, stop) trials of a chunk."""
    n_trials, size = REG_EXPERIMENTS[wildcards.model, wildcards.mesh][0], REG["trials_per_chunk"]
    first = int(wildcards.chunk) * size
    return [first, min(n_trials, first + size)]


def registration_outputs(name):
    """Path of file ``name`` of every configured chunk, ordered by model, mesh, protocol, configured method,
    variant (dgmm.experiments.trials.method_variants), chunk."""
    size = REG["trials_per_chunk"]
    return [
        f"{RESULTS}/registration/{model}/{mesh}/{protocol}/{variant}/{method}/c{chunk}/{name}"
        for (model, mesh), (n_trials, methods, protocols) in sorted(REG_EXPERIMENTS.items())
        for protocol in protocols
        for method in methods
        for variant in method_variants(method, REG["variants"])
        for chunk in range(-(-n_trials // size))
    ]


def dense_sample(wildcards):
    """Evaluation set of the mesh's origin: a registered mesh's own (bunny res4), else the full model's."""
    origin = wildcards.mesh if wildcards.mesh in REGISTRY[wildcards.model] else "full"
    return f"{DATA_DIR}/{wildcards.model}/{origin}_eval.ply"


def registration_mixture(wildcards):
    """The method's fitted mixture, for the methods that use one (``*-c2f``: its paper P2D's)."""
    if not METHODS[wildcards.method].needs_mixture:
        return {}
    source = mixture_source(wildcards.method)
    w = wildcards
    return {"gmm": f"{RESULTS}/registration/{w.model}/{w.mesh}/{w.protocol}/{w.variant}/{source}/gmm.npz"}


# Visual odometry


def odometry_source(entry):
    """``(name, source)`` of a configured sequence: a TUM folder's name, a recording's file stem or bag folder name;
    the source is what ``dgmm.odometry.open_sequence`` reads (``path``, and a recording's topics and ground truth),
    with its ``intrinsics`` when configured. Relative paths are from the repository root."""
    if entry == "synthetic":
        return "synthetic", {
            "path": SYNTHETIC_SEQUENCE,
            "groundtruth": f"{SYNTHETIC_SEQUENCE}/groundtruth.txt",
            "intrinsics": "fr3",
        }
    if isinstance(entry, str):
        entry = {"path": entry}
    source = {**entry, "path": data_dir(entry["path"])}
    path = source["path"].rstrip(os.sep)
    name = os.path.splitext(os.path.basename(path))[0] if path.endswith(".mcap") else os.path.basename(path)
    if "groundtruth" in entry:
        source["groundtruth"] = data_dir(entry["groundtruth"])
    elif "depth_topic" not in entry:  # a TUM folder's own ground truth, read by the job from the folder
        truth = os.path.join(path, "groundtruth.txt")
        source["groundtruth"] = truth if os.path.isfile(truth) else None
    return name, {"groundtruth": None, "intrinsics": ODO["intrinsics"].get(name), **source}


def odometry_sequences():
    """The configured sequences: ``{name: source}`` of those to run (real ones first, then the synthetic one; see
    ``odometry_source``), and ``{name: configured path}`` of the real ones that are missing (the report says they are
    pending)."""
    present, missing = {}, {}
    for entry in sorted(ODO["sequences"], key=lambda entry: entry == "synthetic"):
        name, source = odometry_source(entry)
        if entry == "synthetic" or os.path.exists(source["path"]):
            present[name] = source
        else:
            missing[name] = entry if isinstance(entry, str) else entry["path"]
    return present, missing


ODO_SEQUENCES, ODO_MISSING = odometry_sequences()
ODO_RUNS = odometry_runs(ODO["methods"], ODO["variants"], ODO["protocols"])


def odometry_outputs(name):
    """File ``name`` of every (sequence, run) job, sequences in report order, runs in the configured order."""
    return [f"{ODO_DIR}/{sequence}/{run}/{name}" for sequence in ODO_SEQUENCES for run in ODO_RUNS]


def odometry_inputs(wildcards):
    """The sequence (a TUM folder, a recording file or bag folder) of an odometry job, and its ground-truth file
    when it is one of its own (a recording's)."""
    source = ODO_SEQUENCES[wildcards.sequence]
    truth = source["groundtruth"]
    return {"sequence": source["path"], **({"groundtruth": truth} if "depth_topic" in source and truth else {})}


def odometry_figure_inputs():
    """What Fig 7 reads besides the trajectories: every sequence (a folder's ground truth is read from it) and
    the recordings' ground-truth files."""
    return [source["path"] for source in ODO_SEQUENCES.values()] + [
        source["groundtruth"] for source in ODO_SEQUENCES.values() if "depth_topic" in source and source["groundtruth"]
    ]


def odometry_run_params(wildcards):
    """Method, EM variant and intrinsics of an odometry job, and what it opens the sequence with: the intrinsics
    from ``odometry.intrinsics``, a recording's own entry or, for a TUM folder, its name (the synthetic sequence is
    rendered with freiburg 3's; a recording without them has its camera info)."""
    method, variant = ODO_RUNS[wildcards.run]
    source = ODO_SEQUENCES[wildcards.sequence]
    camera = source["intrinsics"] or (None if "depth_topic" in source else sequence_intrinsics(wildcards.sequence))
    return {
        "method": method,
        "variant": variant or "textbook",
        "intrinsics": camera,
        "depth_topic": source.get("depth_topic"),
        "camera_info_topic": source.get("camera_info_topic"),
    }


# Checks


CHECK_TABLES = {
    # checks.<section> -> {report input key: table}
    "convergence": {"convergence": "convergence.csv"},
    "resampling": {"resampling": "resampling.csv"},
    "optimisers": {"optimisers": "optimisers.csv", "optimisers_seconds": "optimisers_seconds.csv"},
    "timing": {"timing_seconds": "timing_seconds.csv"},
    "identities": {"identities": "identities.csv"},
}


def convergence_outputs():
    """Rows of every configured convergence job: one per (input, variant) of ``checks.convergence``."""
    if "convergence" not in CHECKS:
        return []
    check = CHECKS["convergence"]
    return [
        f"{RESULTS}/checks/convergence/{check['model']}/{name}/{variant}.csv"
        for name in check["inputs"]
        for variant in variants_for(name, FIT["variants"])
    ]


def checks_outputs():
    """The tables of the configured checks: ``{report input key: path}``."""
    return {
        key: f"{RESULTS}/tables/{table}"
        for section, tables in CHECK_TABLES.items()
        if section in CHECKS
        for key, table in tables.items()
    }


# Report


def report_inputs():
    """Named inputs of the report: every stage's tables (the schema gives `odometry` its defaults when absent), the
    configured checks' and the bunny files the pictures use."""
    inputs = {
        "likelihood": rules.likelihood_table.output.likelihood,
        "fig2": rules.fig2.output.table,
        "authors": rules.authors_data.output.table,
        "registration": rules.registration_table.output.errors,
        "registration_seconds": rules.registration_table.output.seconds,
        "odometry": f"{RESULTS}/tables/odometry.csv",
        "fig7": f"{RESULTS}/odometry/fig7.png",
        "odometry_seconds": f"{RESULTS}/tables/odometry_seconds.csv",
    }
    inputs.update(checks_outputs())
    if "bunny" in DATA["models"]:
        inputs.update(
            res4=f"{DATA_DIR}/bunny/res4.ply",
            full=f"{DATA_DIR}/bunny/full.ply",
            dense=f"{DATA_DIR}/bunny/full_eval.ply",
        )
        if PICTURE_BUDGET in DATA["budgets"]:
            inputs.update({method: f"{DATA_DIR}/bunny/{method}{PICTURE_BUDGET}.ply" for method in DATA["methods"]})
    return inputs


def odometry_protocol(wildcards):
    """The protocol of an odometry job's run ("ours", or one of the authors')."""
    return run_protocol(wildcards.run)


def odometry_frames(wildcards):
    """First frames of an odometry job: odometry.frames, capped at odometry.authors_frames for the authors'
    protocols (their per-frame EM runs to convergence: ~10x our CPU per frame)."""
    settings = ODOMETRY_PROTOCOLS[run_protocol(wildcards.run)]
    if settings is None or not settings.capped:
        return ODO["frames"]
    return min(ODO["frames"], ODO["authors_frames"])


def table1_trials():
    """Registration trials Table 1 averages per model: the table1 experiment's (§VI-C: 25), the bunny's being the
    first of Fig 6's; None (every trial) when the config has no table1 experiment."""
    return REG["experiments"]["table1"]["trials"] if "table1" in REG["experiments"] else None


def report_figures():
    """Names of the figures the configured stages allow."""
    configured = {
        f"{name}@{e['max_iter']}" if e["max_iter"] not in (None, FIT["max_iter"]) else name
        for e in FIT["experiments"].values()
        if "bunny" in e["models"]
        for name in e["inputs"]
    }
    configured |= {f"{model}/{mesh}" for model, mesh in REG_EXPERIMENTS}
    return figure_names(report_inputs(), configured)
