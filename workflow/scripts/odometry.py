"""Job: frame-to-frame visual odometry of one (sequence, method); write the trajectory, its ATE, the timings and
the recordings."""
import sys

from threadpoolctl import threadpool_limits

from dgmm.odometry import first_frames, frame_seconds, run_odometry
from dgmm.pixels import FR3
from dgmm.trajectory_metrics import absolute_trajectory_error
from dgmm.tum import read_sequence, write_trajectory
from dgmm.recording import OdometryRecorder
from dgmm.sweep import job_seed
from dgmm.tables import write_csv

smk = snakemake  # noqa: F821 (injected by Snakemake)
sys.stderr = open(smk.log[0], "w")
w, p, out = smk.wildcards, smk.params, smk.output
sequence = read_sequence(smk.input.sequence)
frames, groundtruth = first_frames(sequence, p.frames)
seed = job_seed(p.seed, f"odometry/{w.sequence}/{w.method}", 0)
params = dict(sequence=w.sequence, folder=str(smk.input.sequence), method=w.method, frames=len(frames),
              n_components=p.components, max_iter=p.max_iter, size=p.pixel_size, n_icp_points=p.icp_points,
              seed=seed, root_seed=p.seed)

with threadpool_limits(smk.threads), OdometryRecorder(out.mcap, out.rrd, params=params, groundtruth=groundtruth,
                                                      intrinsics=FR3) as recorder:
    result = run_odometry(sequence, w.method, frames, n_components=p.components, max_iter=p.max_iter,
                          size=p.pixel_size, n_icp_points=p.icp_points, seed=seed, callback=recorder)
    recorder.finish(result.trajectory)
error = absolute_trajectory_error(result.trajectory, sequence.groundtruth)
write_trajectory(out.trajectory, result.trajectory, header=f"dgmm {w.method} odometry of {w.sequence}, seed {seed}")
job = dict(sequence=w.sequence, method=w.method)
write_csv(out.ate, [{**job, "ate_rmse_m": error.rmse, "frames": len(frames)}])
write_csv(out.seconds, [{**job, **row} for row in frame_seconds(result)])
print(f"{w.sequence}/{w.method}: {len(frames)} frames, ATE RMSE {error.rmse:.4f} m", file=sys.stderr)
