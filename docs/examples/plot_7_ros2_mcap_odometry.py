"""
Odometry of a ROS 2 recording (MCAP)
====================================

A robot's depth camera records ``sensor_msgs/msg/Image`` messages into a ROS 2 bag, MCAP by default since ROS 2 Iron.
Here the first 15 depth frames of TUM's fr1/xyz are written as such a recording with
:func:`dgmm.odometry.ros2_mcap.write_recording` (mcap-ros2-support's writer): ``16UC1`` images in millimetres on
``/camera/depth/image_raw``, stamped with TUM's timestamps, and a ``sensor_msgs/msg/CameraInfo`` with the camera's K
on ``/camera/depth/camera_info``. ``dgmm odometry`` runs on it as on the TUM folder, scored against the folder's
ground truth (``--groundtruth``), and writes its trajectory as Foxglove poses and transforms at the recording's
times. The two trajectories are drawn top-down: they differ only by the depth's rounding to whole millimetres (TUM's
PNGs count fifths of a millimetre).
"""

import json
import tempfile
from contextlib import redirect_stdout
from io import StringIO
from pathlib import Path

import matplotlib.pyplot as plt
from mcap.reader import make_reader

import dgmm
from dgmm.cli import main
from dgmm.odometry import CAMERAS, read_sequence, read_trajectory
from dgmm.odometry.ros2_mcap import write_recording

root = Path(dgmm.__file__).resolve().parents[1]
folder = root / "../shared/data/tum/rgbd_dataset_freiburg1_xyz"
sequence = read_sequence(folder)
n = 15
work = Path(tempfile.mkdtemp())
recording = work / "fr1_xyz.mcap"
write_recording(recording, sequence.depth_frames(range(n)), sequence.depth_timestamps[:n], CAMERAS["ros"],
                encoding="16UC1")
with open(recording, "rb") as stream:
    summary = make_reader(stream).get_summary()
for channel_id, count in summary.statistics.channel_message_counts.items():
    channel = summary.channels[channel_id]
    print(f"{channel.topic}: {count} {summary.schemas[channel.schema_id].name} messages")


# %%
# The command a user runs on a recording, and the same on the TUM folder (the intrinsics from its name there, from
# the CameraInfo here). Each prints its result as JSON.
def dgmm_odometry(*args):
    printed = StringIO()
    with redirect_stdout(printed):
        assert main(["odometry", *map(str, args)]) == 0
    return json.loads(printed.getvalue())


runs = {"ROS 2 recording, 16UC1": dgmm_odometry(
    recording, "--depth-topic", "/camera/depth/image_raw", "--groundtruth", folder / "groundtruth.txt",
    "--frames", n, "-o", work / "recording.txt", "--mcap", work / "recording_odometry.mcap"),
    "TUM folder": dgmm_odometry(folder, "--frames", n, "-o", work / "folder.txt")}
for name, result in runs.items():
    print(f"{name:23s} intrinsics {result['intrinsics']:20s} ATE {1000 * result['ate_rmse_m']:.2f} mm")

with open(work / "recording_odometry.mcap", "rb") as stream:
    topics = sorted({channel.topic for _, channel, _ in make_reader(stream).iter_messages()})
print("the run's MCAP:", ", ".join(topics))

# %%
# Both trajectories, top-down in the first camera's frame (x right, z forward).
fig, ax = plt.subplots(figsize=(6, 4.5))
for (name, style), path in zip([("ROS 2 recording, 16UC1", "-"), ("TUM folder", "--")],
                               [work / "recording.txt", work / "folder.txt"]):
    positions = read_trajectory(path).translations
    ax.plot(positions[:, 0], positions[:, 2], style, marker=".", label=name)
ax.set_xlabel("x (m)")
ax.set_ylabel("z (m)")
ax.set_aspect("equal", adjustable="datalim")
ax.set_title(f"fr1/xyz, first {n} frames, gmm-pixels")
ax.legend()
fig.tight_layout()
