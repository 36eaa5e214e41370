"""Visual odometry side by side: our GMM odometry and ICP against small_gicp GICP and Open3D point-to-plane ICP.

Every method runs frame to frame on the same depth frames (fr1/xyz from the mirror by default, all 798), with the
same intrinsics (``ros`` for freiburg 1), the same pose composition (frame ``k+1`` registered onto frame ``k`` from
the identity) and our ATE and one-second RPE (``dgmm.odometry.metrics``), on one thread. Each prints a markdown row
with CPU seconds per frame (``time.process_time``, PNG decoding excluded, as in ``run_odometry``; the machine may
be shared, so CPU time, not wall time).

Peers (the ``peers`` extra): small_gicp GICP on full-resolution clouds voxel-downsampled at 0.02 m and 0.05 m
(10 neighbours for the covariances, max correspondence distance 0.1 m, each frame preprocessed once and kept as
the next frame's target); Open3D point-to-plane ICP on clouds voxel-downsampled at 0.02 m (normals from 30
neighbours within 0.1 m, max correspondence distance 0.1 m, Open3D's default convergence criteria). Open3D needs
``libusb-1.0``; where the system lacks it, the ``libusb-package`` wheel's copy is loaded first.

Usage: ``python benchmarks/odometry_peers.py [SEQUENCE_DIR] [--frames N] [--schedules fast reference]
[--variants textbook authors] [--methods gmm-pixels gmm-points icp] [--peers gicp-0.02 gicp-0.05 open3d]``
(``--peers`` with no name runs none).
"""
import argparse
import os

os.environ.setdefault("OMP_NUM_THREADS", "1")  # before numpy and Open3D start their thread pools

import ctypes  # noqa: E402
import time  # noqa: E402
from pathlib import Path  # noqa: E402

import numpy as np  # noqa: E402
from threadpoolctl import threadpool_limits  # noqa: E402

from dgmm.odometry import (CAMERAS, Trajectory, absolute_trajectory_error, backproject, first_frames,  # noqa: E402
                           read_sequence, relative_pose_error, run_odometry, sequence_intrinsics)

FR1_XYZ = Path(__file__).resolve().parents[2] / "shared" / "data" / "tum" / "rgbd_dataset_freiburg1_xyz"
MAX_DISTANCE = 0.1
"""Max correspondence distance of the peers (m)."""


def small_gicp_method(voxel):
    """small_gicp GICP: (prepare(points) -> (cloud, tree), register(previous, current) -> 4x4 current -> previous)."""
    import small_gicp

    def prepare(points):
        return small_gicp.preprocess_points(points, downsampling_resolution=voxel, num_neighbors=10, num_threads=1)

    def register(previous, current):
        result = small_gicp.align(previous[0], current[0], previous[1], registration_type="GICP",
                                  max_correspondence_distance=MAX_DISTANCE, num_threads=1)
        return result.T_target_source
    return prepare, register


def open3d_method(voxel):
    """Open3D point-to-plane ICP, as :func:`small_gicp_method`."""
    try:
        import open3d as o3d
    except ImportError:  # libusb-1.0 missing from the system: load the wheel's copy, then Open3D finds it
        import libusb_package

        ctypes.CDLL(str(libusb_package.get_library_path()), mode=ctypes.RTLD_GLOBAL)
        import open3d as o3d
    o3d.utility.set_verbosity_level(o3d.utility.VerbosityLevel.Error)
    estimator = o3d.pipelines.registration.TransformationEstimationPointToPlane()

    def prepare(points):
        cloud = o3d.geometry.PointCloud(o3d.utility.Vector3dVector(points)).voxel_down_sample(voxel)
        cloud.estimate_normals(o3d.geometry.KDTreeSearchParamHybrid(radius=0.1, max_nn=30))
        return cloud

    def register(previous, current):
        return o3d.pipelines.registration.registration_icp(current, previous, MAX_DISTANCE, np.eye(4),
                                                           estimator).transformation
    return prepare, register


PEERS = {  # --peers key -> (row name, method)
    "gicp-0.02": ("small_gicp GICP, voxel 0.02 m", lambda: small_gicp_method(0.02)),
    "gicp-0.05": ("small_gicp GICP, voxel 0.05 m", lambda: small_gicp_method(0.05)),
    "open3d": ("Open3D point-to-plane ICP, voxel 0.02 m", lambda: open3d_method(0.02)),
}


def run_peer(sequence, frames, intrinsics, prepare, register):
    """Frame-to-frame odometry with a peer: the trajectory and the CPU seconds of every frame."""
    rotations, translations, cpu = [np.eye(3)], [np.zeros(3)], []
    previous = None
    for index in frames:
        depth = sequence.depth(index)
        start = time.process_time()
        current = prepare(backproject(depth, intrinsics, step=1))
        if previous is not None:
            step = np.asarray(register(previous, current))
            translations.append(rotations[-1] @ step[:3, 3] + translations[-1])
            rotations.append(rotations[-1] @ step[:3, :3])
        cpu.append(time.process_time() - start)
        previous = current
    return Trajectory(sequence.depth_timestamps[frames], np.array(rotations), np.array(translations)), np.array(cpu)


def row(name, schedule, variant, trajectory, groundtruth, cpu):
    """One markdown row: ATE, RPE, CPU seconds per frame."""
    ate = absolute_trajectory_error(trajectory, groundtruth)
    rpe = relative_pose_error(trajectory, groundtruth)
    return (f"| {name} | {schedule} | {variant} | {ate.rmse:.4f} | {rpe.translation_rmse:.4f} | "
            f"{rpe.rotation_rmse_deg:.2f} | {cpu.mean():.3f} |")


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("sequence", nargs="?", default=str(FR1_XYZ))
    parser.add_argument("--frames", type=int, default=10_000)
    parser.add_argument("--schedules", nargs="*", default=["overlap"])
    parser.add_argument("--variants", nargs="+", default=["textbook", "authors"])
    parser.add_argument("--methods", nargs="*", default=["gmm-pixels", "gmm-points", "icp"])
    parser.add_argument("--icp-tol", type=float, default=1e-9, help="our ICP's stopping tolerance (m)")
    parser.add_argument("--peers", nargs="*", default=list(PEERS), choices=list(PEERS),
                        help="the peers to run (none: --peers with no name)")
    parser.add_argument("--intrinsics", default=None, help="CAMERAS key; default from the folder name")
    args = parser.parse_args()
    sequence = read_sequence(args.sequence)
    camera = args.intrinsics or sequence_intrinsics(Path(args.sequence).name)
    intrinsics = CAMERAS[camera]
    frames, _ = first_frames(sequence, args.frames)
    print(f"{Path(args.sequence).name}: {len(frames)} frames, intrinsics {camera}, one thread, load average "
          f"{' '.join(f'{x:.2f}' for x in os.getloadavg())}")
    print("| method | schedule | EM | ATE RMSE (m) | RPE (m/s) | RPE (deg/s) | CPU s/frame |")
    print("|---|---|---|---|---|---|---|")
    with threadpool_limits(1):
        for name, make in (PEERS[key] for key in args.peers):
            trajectory, cpu = run_peer(sequence, frames, intrinsics, *make())
            print(row(name, "–", "–", trajectory, sequence.groundtruth, cpu), flush=True)
        for method in args.methods:
            for schedule in (args.schedules if method != "icp" else ["–"]):
                for variant in (args.variants if method != "icp" else ["–"]):
                    result = run_odometry(sequence, method, frames, intrinsics=intrinsics,
                                          schedule="fast" if schedule == "–" else schedule,
                                          variant="textbook" if variant == "–" else variant, icp_tol=args.icp_tol)
                    print(row(f"ours, {method}", schedule, variant, result.trajectory, sequence.groundtruth,
                              result.cpu_seconds), flush=True)


if __name__ == "__main__":
    main()
