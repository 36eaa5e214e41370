"""`dgmm odometry` on a ROS 2 recording against the same frames as a TUM folder: time per frame and peak memory.

The first N depth frames of a TUM sequence (fr1/xyz from the mirror by default, N = 300) are written as ROS 2 MCAP
recordings (``dgmm.odometry.ros2_mcap.write_recording``: mcap-ros2-support's writer, zstd chunks of 1 MiB, a
CameraInfo with the ``ros`` intrinsics), in 32FC1 metres and 16UC1 millimetres. Then each input runs as a user runs
it, ``dgmm odometry INPUT --frames N`` (gmm-pixels, the ``overlap`` schedule, textbook EM, seed 0; a recording with
``--depth-topic`` and ``--groundtruth`` the folder's), one child process at a time on one BLAS thread, alternating
folder and recordings over the repeats. Each child's wall time, CPU time (user + system) and peak RSS come from
``os.wait4``; the table gives the per-frame wall and CPU of the whole command (imports, the recording's index pass,
reading and converting every frame, the odometry) and its ratio to the folder's, the run's own per-frame CPU of
the odometry alone (its JSON ``cpu_seconds_per_frame``), the ATE and the peak RSS. The 32FC1 recording also runs
on its first N/3 frames: a peak RSS that does not grow with the frames read is the bounded-memory claim.

Reading alone, in this process: seconds per frame to read every depth image of the folder (PNG decoding) and of
each recording (index pass, then streaming).

Usage: ``python benchmarks/odometry_mcap.py [SEQUENCE_DIR] [--frames N] [--repeats R]``.
"""
import argparse
import json
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from dgmm.odometry import CAMERAS, read_sequence
from dgmm.odometry.ros2_mcap import read_recording, write_recording

FR1_XYZ = Path(__file__).resolve().parents[2] / "shared" / "data" / "tum" / "rgbd_dataset_freiburg1_xyz"
DEPTH = "/camera/depth/image_raw"
DGMM = Path(sys.executable).with_name("dgmm")


def run_child(args):
    """Run ``dgmm odometry ARGS``; return its JSON result, wall seconds and resource usage (``os.wait4``)."""
    environment = {**os.environ, "OMP_NUM_THREADS": "1", "OPENBLAS_NUM_THREADS": "1", "MKL_NUM_THREADS": "1"}
    with tempfile.TemporaryFile("w+") as stdout, tempfile.TemporaryFile("w+") as stderr:
        start = time.perf_counter()
        child = subprocess.Popen([str(DGMM), "odometry", *map(str, args)], stdout=stdout, stderr=stderr,
                                 env=environment)
        _, status, usage = os.wait4(child.pid, 0)
        wall = time.perf_counter() - start
        child.returncode = os.waitstatus_to_exitcode(status)
        stdout.seek(0), stderr.seek(0)
        if child.returncode != 0:
            raise SystemExit(f"dgmm odometry {' '.join(map(str, args))} failed: {stderr.read().strip()}")
        return json.loads(stdout.read()), wall, usage


def read_every_frame(open_source, n_frames):
    """CPU seconds per frame to open a sequence (a recording's index pass) and read its first frames."""
    start = time.process_time()
    for _ in open_source().depth_frames(range(n_frames)):
        pass
    return (time.process_time() - start) / n_frames


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("sequence", nargs="?", type=Path, default=FR1_XYZ)
    parser.add_argument("--frames", type=int, default=300)
    parser.add_argument("--repeats", type=int, default=2)
    args = parser.parse_args()
    sequence, n = read_sequence(args.sequence), args.frames
    folder = Path(tempfile.mkdtemp(prefix="dgmm-odometry-mcap-"))
    inputs = {"TUM folder": [args.sequence]}
    for encoding in ("32FC1", "16UC1"):
        path = folder / f"{encoding}.mcap"
        write_recording(path, sequence.depth_frames(range(n)), sequence.depth_timestamps[:n], CAMERAS["ros"],
                        encoding=encoding)
        inputs[f"MCAP {encoding}"] = [path, "--depth-topic", DEPTH, "--groundtruth", sequence.groundtruth_file]
        print(f"{path.name}: {path.stat().st_size / 2**20:.0f} MiB for {n} frames", file=sys.stderr)

    print(f"reading TUM folder: {1000 * read_every_frame(lambda: sequence, n):.2f} CPU ms per frame", file=sys.stderr)
    for name, command in list(inputs.items())[1:]:
        cpu = read_every_frame(lambda: read_recording(command[0], DEPTH), n)
        print(f"reading {name} (index pass and stream): {1000 * cpu:.2f} CPU ms per frame", file=sys.stderr)

    runs = {**{name: (command, n) for name, command in inputs.items()},
            f"MCAP 32FC1, first {n // 3} frames": (inputs["MCAP 32FC1"], n // 3)}
    measured = {name: [] for name in runs}
    for repeat in range(args.repeats):
        order = list(runs) if repeat % 2 == 0 else list(reversed(runs))
        for name in order:
            command, frames = runs[name]
            result, wall, usage = run_child([*command, "--frames", frames])
            measured[name].append((result, wall, usage.ru_utime + usage.ru_stime, usage.ru_maxrss / 1024))
            print(f"{name}: {wall:.1f} s wall", file=sys.stderr)

    def best(name, column):
        return min(values[column] for values in measured[name])

    base_wall, base_cpu = best("TUM folder", 1) / n, best("TUM folder", 2) / n
    print(f"\n{n} frames of {args.sequence.name}, gmm-pixels (overlap, textbook EM, seed 0), one thread, best of "
          f"{args.repeats}\n")
    print("| input | frames | wall s / frame | CPU s / frame | ratio to the folder (wall, CPU) | odometry CPU s / frame "
          "| ATE (m) | peak RSS (MiB) |")
    print("|---|---|---|---|---|---|---|---|")
    for name, (_, frames) in runs.items():
        wall, cpu = best(name, 1) / frames, best(name, 2) / frames
        result = measured[name][0][0]
        ratios = f"{wall / base_wall:.3f}, {cpu / base_cpu:.3f}" if frames == n else "–"
        print(f"| {name} | {frames} | {wall:.4f} | {cpu:.4f} | {ratios} | "
              f"{min(values[0]['cpu_seconds_per_frame'] for values in measured[name]):.4f} | "
              f"{result['ate_rmse_m']:.5f} | {max(values[3] for values in measured[name]):.0f} |")


if __name__ == "__main__":
    main()
