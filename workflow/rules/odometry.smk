# Visual odometry (paper §V "Visual Odometry", Fig 6): frame-to-frame odometry of the first odometry.frames depth
# frames of a TUM RGB-D sequence with each method, one job per (sequence, method). The sequence is the configured
# folder (odometry.sequence, e.g. an unpacked rgbd_dataset_freiburg3_long_office_household) when it exists, else the
# synthetic one, rendered once from the seed into results/odometry/synthetic/sequence/. Under
# results/odometry/{sequence}/{method}/ ({sequence}: the folder's name, or "synthetic"):
#   trajectory.txt   the estimated trajectory, TUM format (camera -> first camera)
#   ate.csv          ATE RMSE against the ground truth after a rigid alignment, and the frame count (deterministic)
#   seconds.csv      each frame's model and registration time (kept apart so that ate.csv is byte-identical)
#   odometry.mcap    per-frame timings, the estimated and ground-truth trajectories (foxglove.PosesInFrame)
#   odometry.rrd     the camera path and each frame's mixture (or ICP points) on the timeline `frame`
# and results/tables/odometry.csv (ATE), odometry_seconds.csv (mean timings), results/odometry/fig6.png.
import re

from dgmm.odometry import METHODS as ODOMETRY_METHODS

ODO_JOB = f"{ODO_DIR}/{{sequence}}/{{method}}"


rule odometry_synthetic:
    input:
        meshes=[f"{DATA_DIR}/{mesh}.ply" for mesh in ODO["synthetic"]["meshes"]],
    output:
        sequence=directory(SYNTHETIC_SEQUENCE),
    log:
        f"{RESULTS}/logs/odometry/synthetic.log",
    threads: 1
    resources:
        mem_mb=1000,
        runtime=60,
        cpus_per_task=1,
    params:
        frames=ODO["frames"],
        seed=config["seed"],
    script:
        "../scripts/odometry_synthetic.py"


rule odometry_run:
    input:
        sequence=ODO_FOLDER,
    output:
        trajectory=f"{ODO_JOB}/trajectory.txt",
        ate=f"{ODO_JOB}/ate.csv",
        seconds=f"{ODO_JOB}/seconds.csv",
        mcap=f"{ODO_JOB}/odometry.mcap",
        rrd=f"{ODO_JOB}/odometry.rrd",
    log:
        f"{RESULTS}/logs/odometry/{{sequence}}/{{method}}.log",
    wildcard_constraints:
        sequence=re.escape(ODO_SEQUENCE),
        method="|".join(ODOMETRY_METHODS),
    threads: 1
    resources:
        mem_mb=1500,
        runtime=240,
        cpus_per_task=1,
    params:
        seed=config["seed"],
        frames=ODO["frames"],
        components=ODO["components"],
        max_iter=ODO["max_iter"],
        pixel_size=ODO["pixel_size"],
        icp_points=ODO["icp_points"],
    script:
        "../scripts/odometry.py"


rule odometry_table:
    input:
        ate=odometry_outputs("ate.csv"),
        seconds=odometry_outputs("seconds.csv"),
    output:
        ate=f"{RESULTS}/tables/odometry.csv",
        seconds=f"{RESULTS}/tables/odometry_seconds.csv",
    log:
        f"{RESULTS}/logs/tables/odometry.log",
    threads: 1
    script:
        "../scripts/odometry_tables.py"


rule odometry_figure:
    input:
        sequence=ODO_FOLDER,
        trajectories=odometry_outputs("trajectory.txt"),
    output:
        png=report(f"{ODO_DIR}/fig6.png", caption="../report/odometry_fig6.rst", category="Figures"),
    log:
        f"{RESULTS}/logs/odometry/fig6.log",
    threads: 1
    params:
        methods=ODO["methods"],
        sequence=ODO_SEQUENCE,
        plane=ODO["plane"],
    script:
        "../scripts/odometry_figure.py"


rule odometry:
    input:
        rules.odometry_table.output,
        rules.odometry_figure.output,
        odometry_outputs("odometry.mcap"),
        odometry_outputs("odometry.rrd"),
