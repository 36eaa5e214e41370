"""Job: frame-to-frame visual odometry of one (sequence, run); write the trajectory, its ATE and RPE, the timings
and the recordings."""
from dgmm.runtime.job_server import hand_over

hand_over()  # in a sweep, the rest runs in a fork of the job server, its imports already loaded

import sys

from threadpoolctl import threadpool_limits

from dgmm.experiments.sweep import job_seed
from dgmm.odometry import first_frames, frame_seconds, open_sequence, run_odometry
from dgmm.odometry.metrics import drift_metrics
from dgmm.odometry.pixels import PIXEL_STEP
from dgmm.odometry.protocols import PROTOCOLS
from dgmm.odometry.tum import write_trajectory
from dgmm.recording import OdometryRecorder
from dgmm.runtime.tables import write_csv

smk = snakemake  # noqa: F821 (injected by Snakemake)
sys.stderr = open(smk.log[0], "w")
w, p, out = smk.wildcards, smk.params, smk.output
method, variant = p.run["method"], p.run["variant"]
sequence = open_sequence(smk.input.sequence, p.run["depth_topic"], p.run["camera_info_topic"],
                         getattr(smk.input, "groundtruth", None))
camera, intrinsics = sequence.camera(p.run["intrinsics"])
frames, groundtruth = first_frames(sequence, p.frames, require_groundtruth=False)
seed = job_seed(p.seed, f"odometry/{w.sequence}/{w.run}", 0)
options = dict(intrinsics=intrinsics, n_components=p.components, schedule=p.schedule, warm_iter=p.warm_iter or None,
               variant=variant, size=p.pixel_size, protocol=p.protocol, n_icp_points=p.icp_points, seed=seed)
settings = PROTOCOLS[p.protocol]  # another protocol's schedule (if it has one) and pixel size replace the configured
schedule, size = (p.schedule, p.pixel_size) if settings is None else (settings.schedule or p.schedule, settings.size)
params = dict(sequence=w.sequence, folder=str(smk.input.sequence), method=method, variant=variant,
              intrinsics=camera, frames=len(frames), n_components=p.components, protocol=p.protocol, schedule=schedule,
              warm_iter=p.warm_iter, size=size, n_icp_points=p.icp_points, seed=seed, root_seed=p.seed)

with threadpool_limits(smk.threads), OdometryRecorder(out.mcap, out.rrd, params=params, groundtruth=groundtruth,
                                                      intrinsics=intrinsics, camera_frame=sequence.camera_frame,
                                                      pixel_step=PIXEL_STEP) as recorder:
    result = run_odometry(sequence, method, frames, callback=recorder, **options)
    recorder.finish(result.trajectory)
metrics = drift_metrics(result.trajectory, sequence.groundtruth)  # all None without ground truth
write_trajectory(out.trajectory, result.trajectory, header=f"dgmm {w.run} odometry of {w.sequence}, seed {seed}")
job = dict(sequence=w.sequence, method=method, variant=variant if method != "icp" else "")
metrics = {key: "" if value is None else value for key, value in metrics.items()}
mixture = method != "icp"
write_csv(out.ate, [{**job, "schedule": schedule if mixture else "", "frames": len(frames), **metrics,
                     "protocol": p.protocol if mixture else ""}])
write_csv(out.seconds, [{**job, "protocol": p.protocol if mixture else "", **row} for row in frame_seconds(result)])
print(f"{w.sequence}/{w.run}: {len(frames)} frames, {metrics}, {result.cpu_seconds.mean():.3f} CPU s per frame",
      file=sys.stderr)
