# Visual odometry (paper §VI-D "Visual Odometry", Fig 7): frame-to-frame odometry of the first odometry.frames depth
# frames of every configured sequence that exists (odometry.sequences: TUM RGB-D folders and ROS 2 recordings; missing
# ones are reported pending) and of the synthetic one (rendered once from the seed into results/odometry/synthetic/sequence/), one job per
# (sequence, run): a run is a GMM method with an EM variant (gmm-pixels-textbook, gmm-pixels-authors; the plain-point
# GMM runs textbook EM only, the same algorithm as the authors' on unit sizes: gmm-points-textbook) or icp, under
# protocol "ours" (odometry.schedule, odometry.pixel_size), and gmm-pixels under each of the authors' protocols in
# odometry.protocols (gmm-pixels-authors-patch, gmm-points-authors-patch, gmm-pixels-authors-disparity:
# dgmm.odometry.protocols) over the first
# min(frames, authors_frames) frames. ate.csv's `protocol` column says which protocol a row ran ("" for icp).
# Under results/odometry/{sequence}/{run}/ ({sequence}: the folder's name, a recording's file stem, or "synthetic"):
#   trajectory.txt   the estimated trajectory, TUM format (camera -> first camera)
#   ate.csv          ATE RMSE and the one-second RPE against the ground truth (empty without one), and the frame count
#   seconds.csv      each frame's model and registration time, and CPU time (kept apart: ate.csv is byte-identical)
#   odometry.mcap    per-frame timings, the estimated and ground-truth trajectories (foxglove.PosesInFrame)
#   odometry.rrd     the camera path and each frame's mixture (or ICP points) on the timeline `frame`
# and results/tables/odometry.csv (ATE, RPE), odometry_seconds.csv (mean timings), results/odometry/fig7.png.
import re

ODO_JOB = f"{ODO_DIR}/{{sequence}}/{{run}}"


rule odometry_synthetic:
    input:
        meshes=[f"{DATA_DIR}/{mesh}.ply" for mesh in ODO["synthetic"]["meshes"]],
    output:
        sequence=directory(SYNTHETIC_SEQUENCE),
    log:
        f"{RESULTS}/logs/odometry/synthetic.log",
    benchmark:
        f"{RESULTS}/benchmarks/odometry_synthetic.tsv"
    priority: PRIORITY["odometry_synthetic"]
    threads: 1
    resources:
        mem_mb=1000,
        runtime=60,
        cpus_per_task=1,
    params:
        frames=ODO["synthetic"]["frames"],
        seed=config["seed"],
    script:
        "../scripts/odometry_synthetic.py"


rule odometry_run:
    input:
        unpack(odometry_inputs),
    output:
        trajectory=f"{ODO_JOB}/trajectory.txt",
        ate=f"{ODO_JOB}/ate.csv",
        seconds=f"{ODO_JOB}/seconds.csv",
        mcap=f"{ODO_JOB}/odometry.mcap",
        rrd=f"{ODO_JOB}/odometry.rrd",
    log:
        f"{RESULTS}/logs/odometry/{{sequence}}/{{run}}.log",
    benchmark:
        f"{RESULTS}/benchmarks/odometry_run/{{sequence}}/{{run}}.tsv"
    wildcard_constraints:
        sequence="|".join(map(re.escape, ODO_SEQUENCES)),
        run="|".join(map(re.escape, ODO_RUNS)),
    priority: PRIORITY["odometry_run"]
    threads: 1
    resources:
        mem_mb=1500,
        runtime=240,
        cpus_per_task=1,
    params:
        run=odometry_run_params,
        seed=config["seed"],
        frames=odometry_frames,
        protocol=odometry_protocol,
        components=ODO["components"],
        schedule=ODO["schedule"],
        warm_iter=ODO["warm_iter"],
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
    benchmark:
        f"{RESULTS}/benchmarks/odometry_table.tsv"
    threads: 1
    resources:
        mem_mb=500,
        runtime=5,
        cpus_per_task=1,
    params:
        missing=ODO_MISSING,
    script:
        "../scripts/odometry_tables.py"


rule odometry_figure:
    input:
        sequences=odometry_figure_inputs(),
        trajectories=odometry_outputs("trajectory.txt"),
    output:
        png=report(f"{ODO_DIR}/fig7.png", caption="../report/odometry_fig7.rst", category="Figures"),
    log:
        f"{RESULTS}/logs/odometry/fig7.log",
    benchmark:
        f"{RESULTS}/benchmarks/odometry_figure.tsv"
    threads: 1
    resources:
        mem_mb=1000,  # measured: 252 MB peak, 0.2 s on tests/config.yaml
        runtime=5,
        cpus_per_task=1,
    params:
        sequences=list(ODO_SEQUENCES),
        groundtruth=[source["groundtruth"] for source in ODO_SEQUENCES.values()],
        runs=list(ODO_RUNS),
        plane=ODO["plane"],
    script:
        "../scripts/odometry_figure.py"


rule odometry:
    input:
        rules.odometry_table.output,
        rules.odometry_figure.output,
        odometry_outputs("odometry.mcap"),
        odometry_outputs("odometry.rrd"),
