"""ROS 2 recordings in MCAP as depth sequences: a robot's own ``ros2 bag record`` of a depth camera, read streaming.

A recording is an ``.mcap`` file or a ROS 2 bag folder (``metadata.yaml`` and the ``.mcap`` files it lists, in
order; MCAP is rosbag2's default storage since ROS 2 Iron). Depth frames are the messages of one topic:

- ``sensor_msgs/msg/Image`` (CDR, decoded by ``mcap-ros2-support``) or Foxglove's ``foxglove.RawImage`` (protobuf,
  decoded by ``mcap-protobuf-support``), in the encodings of :data:`DEPTH_ENCODINGS` (REP 118: ``16UC1``
  millimetres, 0 = no measurement; ``32FC1`` metres, NaN or ±Inf = no measurement);
- stamped with their header's time (``header.stamp``; RawImage's ``timestamp``), which must increase;
- all of one size.

Intrinsics come from the first ``sensor_msgs/msg/CameraInfo`` (or ``foxglove.CameraCalibration``) message of the
camera-info topic: its K matrix and image size (lens distortion is not modelled, as for TUM's cameras).

:func:`read_recording` reads the recording once to index it (every message's stamp, size and encoding, checking
each chunk's CRC), holding only those numbers; :meth:`McapSequence.depth_frames` then reads it again front to
back, converting one message at a time, so memory stays bounded by a few frames whatever the recording's length.
:func:`write_recording` writes depth images as such a recording (mcap-ros2-support's writer), e.g. from a TUM
folder.
"""
from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from dgmm.errors import DataError, InputError, needs
from dgmm.files import atomic_open
from dgmm.odometry.pixels import Intrinsics, parse_intrinsics
from dgmm.odometry.tum import Trajectory, read_trajectory

with needs("ros2"):
    import yaml
    from mcap.reader import make_reader
    from mcap_protobuf.decoder import DecoderFactory as ProtobufDecoderFactory
    from mcap_ros2.decoder import DecoderFactory as Ros2DecoderFactory
    from mcap_ros2.writer import Writer

DEPTH_ENCODINGS = {"16UC1": (np.uint16, 1000.0), "32FC1": (np.float32, 1.0)}
"""Depth image encoding -> (pixel type, units per metre): REP 118's millimetres and metres."""

_TIME = "builtin_interfaces/Time\nint32 sec\nuint32 nanosec\n"
_HEADER = "std_msgs/Header\nbuiltin_interfaces/Time stamp\nstring frame_id\n"
_SEPARATOR = "=" * 80 + "\nMSG: "

IMAGE_MSGDEF = ("std_msgs/Header header\nuint32 height\nuint32 width\nstring encoding\nuint8 is_bigendian\n"
                "uint32 step\nuint8[] data\n" + _SEPARATOR + _HEADER + _SEPARATOR + _TIME)
"""``sensor_msgs/msg/Image`` as ROS 2 bags store its schema: the message's fields, then each nested type's after a
line of ``=`` and ``MSG: package/Type`` (comments and constants left out)."""

CAMERA_INFO_MSGDEF = ("std_msgs/Header header\nuint32 height\nuint32 width\nstring distortion_model\nfloat64[] d\n"
                      "float64[9] k\nfloat64[9] r\nfloat64[12] p\nuint32 binning_x\nuint32 binning_y\n"
                      "sensor_msgs/RegionOfInterest roi\n" + _SEPARATOR + _HEADER + _SEPARATOR + _TIME + _SEPARATOR
                      + "sensor_msgs/RegionOfInterest\nuint32 x_offset\nuint32 y_offset\nuint32 height\n"
                        "uint32 width\nbool do_rectify\n")
"""``sensor_msgs/msg/CameraInfo``, in the same form as :data:`IMAGE_MSGDEF`."""


# ------------------------------------------------------------------------------------------------ messages
@dataclass(frozen=True)
class _Image:
    """The fields of a depth image message that dgmm reads, whichever schema carried them."""

    stamp_ns: int
    frame_id: str
    width: int
    height: int
    encoding: str
    big_endian: bool
    step: int
    data: bytes


def _ros2_image(message):
    stamp = message.header.stamp
    return _Image(stamp.sec * 10**9 + stamp.nanosec, message.header.frame_id, message.width, message.height,
                  message.encoding, bool(message.is_bigendian), message.step, message.data)


def _foxglove_image(message):
    return _Image(message.timestamp.seconds * 10**9 + message.timestamp.nanos, message.frame_id, message.width,
                  message.height, message.encoding, False, message.step, message.data)


IMAGE_SCHEMAS = {"sensor_msgs/msg/Image": _ros2_image, "foxglove.RawImage": _foxglove_image}
"""Schema name of a depth image message -> its reader (Foxglove's RawImage has no byte order: little-endian)."""

CAMERA_INFO_SCHEMAS = {"sensor_msgs/msg/CameraInfo": lambda message: (message.k, message.width, message.height),
                       "foxglove.CameraCalibration": lambda message: (message.K, message.width, message.height)}
"""Schema name of a camera-info message -> its (row-major 3×3 K, width, height)."""


def _depth_metres(image, source):
    """An image message's pixels as depth in metres, shape (height, width), 0 where there is no measurement."""
    kind, units = DEPTH_ENCODINGS[image.encoding]
    dtype = np.dtype(kind).newbyteorder(">" if image.big_endian else "<")
    row_bytes = image.width * dtype.itemsize
    if image.step < row_bytes or len(image.data) < image.step * image.height:
        raise DataError(f"{source}: {len(image.data)} bytes of data for {image.height} rows of step {image.step} "
                        f"({image.width} {image.encoding} pixels a row)")
    rows = np.frombuffer(image.data, np.uint8, count=image.step * image.height).reshape(image.height, image.step)
    depth = np.true_divide(rows[:, :row_bytes].view(dtype), units, dtype=np.float64)
    if dtype.kind == "f":  # REP 118: NaN and ±Inf, and here anything not in front, are no measurement
        depth[~(np.isfinite(depth) & (depth > 0))] = 0.0
    return depth


# ------------------------------------------------------------------------------------------------ files
def recording_files(path):
    """The MCAP files of a recording: the file itself, or those a bag folder's ``metadata.yaml`` lists, in order.

    Raises
    ------
    DataError
        No such file; a folder without ``metadata.yaml``, whose metadata is not rosbag2's, whose storage is not
        MCAP, or one of whose files is missing.
    """
    path = Path(path)
    if not path.is_dir():
        if not path.is_file():
            raise DataError(f"{path}: no such file")
        return (path,)
    metadata = path / "metadata.yaml"
    try:
        info = yaml.safe_load(metadata.read_text())["rosbag2_bagfile_information"]
        storage, names = info.get("storage_identifier"), info.get("relative_file_paths") or []
    except OSError as exc:
        raise DataError(f"{metadata}: cannot read ({exc.strerror or exc}): not a ROS 2 bag folder") from None
    except (yaml.YAMLError, TypeError, KeyError, AttributeError):
        raise DataError(f"{metadata}: not a rosbag2 metadata file (no rosbag2_bagfile_information)") from None
    if storage != "mcap":
        raise DataError(f"{metadata}: storage {storage!r}; dgmm reads MCAP bags (ros2 bag convert them to mcap)")
    files = tuple(path / name for name in names)
    if not files:
        raise DataError(f"{metadata}: lists no files")
    for file in files:
        if not file.is_file():
            raise DataError(f"{file}: listed in {metadata} but missing")
    return files


def _messages(file, topics, validate_crcs=False):
    """Decoded messages of ``topics`` in one MCAP file, in log-time order, as (topic, schema name, message).

    Raises
    ------
    DataError
        The file is truncated or corrupt (the mcap reader and the decoders raise many types on a damaged file:
        ``McapError``, ``struct.error``, ``ValueError``, zstd's errors; any of them is the file's fault here).
    """
    try:
        with open(file, "rb") as stream:
            reader = make_reader(stream, validate_crcs=validate_crcs,
                                 decoder_factories=[Ros2DecoderFactory(), ProtobufDecoderFactory()])
            for schema, channel, _, decoded in reader.iter_decoded_messages(topics):
                yield channel.topic, "" if schema is None else schema.name, decoded
    except OSError as exc:
        raise DataError(f"{file}: cannot read ({exc.strerror or exc})") from None
    except Exception as exc:  # noqa: BLE001 (see above)
        raise DataError(f"{file}: not a readable MCAP file, truncated or corrupt ({type(exc).__name__}: {exc}); "
                        "the mcap CLI's `mcap recover` may save its readable part") from None


def _topics(files):
    """``topic (schema)`` of every channel of the files, for the errors that need to list them."""
    found = {}
    for file in files:
        try:
            with open(file, "rb") as stream:
                reader = make_reader(stream)
                summary = reader.get_summary()
                channels = (summary.channels.values() if summary is not None else
                            {channel.id: channel for _, channel, _ in reader.iter_messages()}.values())
                schemas = {} if summary is None else summary.schemas
                found.update({channel.topic: getattr(schemas.get(channel.schema_id), "name", "?")
                              for channel in channels})
        except Exception:  # noqa: BLE001 (a damaged file lists what could be read)
            continue
    return ", ".join(f"{topic} ({schema})" for topic, schema in sorted(found.items())) or "none"


def default_camera_info_topic(depth_topic):
    """The camera-info topic beside an image topic (ROS's convention): ``/camera/depth/camera_info`` for
    ``/camera/depth/image_raw``."""
    return depth_topic.rpartition("/")[0] + "/camera_info"


def _intrinsics(schema, message, source, size):
    """Intrinsics from a camera-info message's K matrix, for images of ``size`` (width, height)."""
    k, width, height = CAMERA_INFO_SCHEMAS[schema](message)
    k = np.asarray(k, dtype=np.float64)
    if k.shape != (9,) or not np.all(np.isfinite(k)) or min(k[0], k[4]) <= 0:
        raise DataError(f"{source}: K {k.tolist()} is not a calibration (fx = K[0], fy = K[4] must be > 0)")
    if (width, height) != size:
        raise DataError(f"{source}: width x height {width}x{height}, the depth images are {size[0]}x{size[1]}")
    return Intrinsics(fx=float(k[0]), fy=float(k[4]), cx=float(k[2]), cy=float(k[5]), width=int(width),
                      height=int(height))


# ------------------------------------------------------------------------------------------------ sequences
@dataclass(frozen=True)
class McapSequence:
    """A ROS 2 recording's depth frames (``dgmm.odometry.sequence.DepthSequence``), streamed from its files.

    Attributes
    ----------
    path : pathlib.Path
        The ``.mcap`` file or the bag folder.
    files : tuple of pathlib.Path
        Its MCAP files, in order.
    depth_topic : str
    depth_timestamps : ndarray of shape (n_frames,)
        Header stamps, seconds.
    image_size : tuple of int
        (width, height) of every depth image.
    camera_frame : str
        The images' ``frame_id``.
    camera_info : tuple or None
        (text, Intrinsics) from the camera-info topic's first message, or None when it has none.
    camera_info_topic : str
    groundtruth : Trajectory or None
    groundtruth_file : pathlib.Path or None
    """

    path: Path
    files: tuple
    depth_topic: str
    depth_timestamps: np.ndarray
    image_size: tuple
    camera_frame: str
    camera_info: tuple | None
    camera_info_topic: str
    groundtruth: Trajectory | None
    groundtruth_file: Path | None

    @property
    def name(self):
        """The file's stem, or the bag folder's name."""
        return self.path.name if self.path.is_dir() else self.path.stem

    def __len__(self):
        return len(self.depth_timestamps)

    def frame_source(self, index):
        """``RECORDING: TOPIC message INDEX``."""
        return f"{self.path}: {self.depth_topic} message {index}"

    def depth_frames(self, indices):
        """Depth of each frame of ``indices`` (increasing), in metres, read one message at a time.

        Raises
        ------
        InputError
            The indices do not increase.
        """
        indices = [int(index) for index in indices]
        if any(later <= earlier for earlier, later in zip(indices, indices[1:])):
            raise InputError(f"{self.path}: frames of a recording stream in order; indices must increase")
        wanted, index = iter(indices), 0
        target = next(wanted, None)
        for file in self.files:
            if target is None:
                return
            for _, schema, message in _messages(file, [self.depth_topic]):
                if index == target:
                    yield _depth_metres(IMAGE_SCHEMAS[schema](message), self.frame_source(index))
                    target = next(wanted, None)
                    if target is None:
                        return
                index += 1

    def camera(self, intrinsics=None):
        """The depth camera: ``intrinsics`` (``fr1|fr2|fr3|ros|FX,FY,CX,CY``, at this recording's image size) when
        given, else the camera-info topic's.

        Returns
        -------
        text : str
            ``intrinsics``, or the recorded K's ``FX,FY,CX,CY``.
        intrinsics : dgmm.odometry.pixels.Intrinsics

        Raises
        ------
        InputError
            Neither is there (the message lists the recording's topics).
        """
        if intrinsics is not None:
            return intrinsics, parse_intrinsics(intrinsics, *self.image_size)
        if self.camera_info is None:
            raise InputError(f"{self.path}: no camera info on {self.camera_info_topic} (topics: "
                             f"{_topics(self.files)}): name its topic (sensor_msgs/msg/CameraInfo) or give the "
                             f"intrinsics")
        return self.camera_info


def read_recording(path, depth_topic, camera_info_topic=None, *, groundtruth=None):
    """Index a ROS 2 recording's depth frames: their stamps, size and encoding, and the camera's intrinsics.

    Parameters
    ----------
    path : path-like
        An ``.mcap`` file or a ROS 2 bag folder (``metadata.yaml`` and its ``.mcap`` files).
    depth_topic : str
        ``sensor_msgs/msg/Image`` or ``foxglove.RawImage`` messages in an encoding of :data:`DEPTH_ENCODINGS`.
    camera_info_topic : str, optional
        ``sensor_msgs/msg/CameraInfo`` (or ``foxglove.CameraCalibration``) messages; by default the topic beside
        the depth topic (:func:`default_camera_info_topic`). None there is no error until the intrinsics are
        asked for without being given (:meth:`McapSequence.camera`).
    groundtruth : path-like, optional
        A TUM trajectory file of the camera's ground-truth poses, on the header stamps' clock.

    Returns
    -------
    McapSequence

    Raises
    ------
    DataError
        One line naming the file, topic or field: a missing file or topic (listing the recording's topics), a
        topic of another message type, an unsupported encoding, images of two sizes, header stamps that do not
        increase, a camera-info message that is no calibration or is for another image size, a truncated or
        corrupt file.
    """
    path = Path(path)
    files = recording_files(path)
    info_topic = camera_info_topic or default_camera_info_topic(depth_topic)
    stamps, first, camera_info = [], None, None
    for file in files:
        for topic, schema, message in _messages(file, [depth_topic, info_topic], validate_crcs=True):
            if topic == info_topic != depth_topic:
                if camera_info is None:
                    camera_info = (schema, message, f"{path}: {topic}")
                continue
            source = f"{path}: {depth_topic} message {len(stamps)}"
            if schema not in IMAGE_SCHEMAS:
                raise DataError(f"{source}: a {schema} message; depth images are {' or '.join(IMAGE_SCHEMAS)}")
            image = IMAGE_SCHEMAS[schema](message)
            if image.encoding not in DEPTH_ENCODINGS:
                raise DataError(f"{source}: encoding {image.encoding!r}; dgmm reads depth images in "
                                f"{' or '.join(DEPTH_ENCODINGS)} (REP 118)")
            if first is None:
                first = image
            if (image.width, image.height) != (first.width, first.height):
                raise DataError(f"{source}: {image.width}x{image.height} image; message 0 is "
                                f"{first.width}x{first.height} (all depth images must be of one size)")
            if stamps and image.stamp_ns <= stamps[-1]:
                raise DataError(f"{source}: header stamp {image.stamp_ns / 1e9:.9f} s is not after the previous "
                                f"message's {stamps[-1] / 1e9:.9f} s (timestamps must increase)")
            stamps.append(image.stamp_ns)
    if first is None:
        raise DataError(f"{path}: no messages on topic {depth_topic} (topics: {_topics(files)})")
    size = (first.width, first.height)
    if camera_info is not None:
        schema, message, source = camera_info
        if schema not in CAMERA_INFO_SCHEMAS:
            raise DataError(f"{source}: a {schema} message; camera info is {' or '.join(CAMERA_INFO_SCHEMAS)}")
        recorded = _intrinsics(schema, message, source, size)
        camera_info = (f"{recorded.fx:.9g},{recorded.fy:.9g},{recorded.cx:.9g},{recorded.cy:.9g}", recorded)
    return McapSequence(path, files, depth_topic, np.array(stamps, dtype=np.int64) / 1e9, size, first.frame_id,
                        camera_info, info_topic, None if groundtruth is None else read_trajectory(groundtruth),
                        None if groundtruth is None else Path(groundtruth))


# ------------------------------------------------------------------------------------------------ writing
def _encoded(depth, kind, units):
    """Depth in metres as little-endian pixels of ``kind`` at ``units`` per metre (integers rounded)."""
    depth = np.asarray(depth, dtype=np.float64)
    limit = np.iinfo(kind).max / units if np.issubdtype(kind, np.integer) else np.finfo(kind).max / units
    if depth.ndim != 2 or not np.all(np.isfinite(depth)) or depth.min() < 0 or depth.max() > limit:
        raise InputError(f"depth must be a finite 2-D array in [0, {limit:.6g}] m, got shape {depth.shape}")
    pixels = depth * units
    return (np.rint(pixels) if np.issubdtype(kind, np.integer) else pixels).astype(np.dtype(kind).newbyteorder("<"))


def write_recording(path, depths, timestamps, intrinsics=None, *, encoding="32FC1",
                    depth_topic="/camera/depth/image_raw", camera_info_topic=None,
                    frame_id="camera_depth_optical_frame"):
    """Write depth images as a ROS 2 recording: ``sensor_msgs/msg/Image`` messages and, with ``intrinsics``, one
    ``sensor_msgs/msg/CameraInfo`` (written through a temporary file and a rename).

    Parameters
    ----------
    path : path-like
        The ``.mcap`` file.
    depths : iterable of array-like of shape (height, width)
        Metres, 0 = no measurement (e.g. ``TumSequence.depth_frames(range(n))``); read one at a time.
    timestamps : array-like of shape (n_frames,)
        Seconds: header stamps and log times.
    intrinsics : dgmm.odometry.pixels.Intrinsics, optional
        Written as a CameraInfo message (K, image size; no distortion) before the first image.
    encoding : {"16UC1", "32FC1"}
        Millimetres as uint16 (depth rounded to 1 mm, at most 65.535 m), or metres as float32.
    depth_topic : str
    camera_info_topic : str, optional
        Defaults to the topic beside ``depth_topic`` (:func:`default_camera_info_topic`).
    frame_id : str
        The images' and the camera info's ``header.frame_id``.
    """
    if encoding not in DEPTH_ENCODINGS:
        raise InputError(f"encoding must be one of {' or '.join(DEPTH_ENCODINGS)}, got {encoding!r}")
    kind, units = DEPTH_ENCODINGS[encoding]
    stamps = [int(round(float(stamp) * 1e9)) for stamp in timestamps]

    def header(ns):
        return {"stamp": {"sec": ns // 10**9, "nanosec": ns % 10**9}, "frame_id": frame_id}

    with atomic_open(path) as stream, Writer(stream) as writer:
        image_schema = writer.register_msgdef("sensor_msgs/msg/Image", IMAGE_MSGDEF)
        if intrinsics is not None:
            k = [intrinsics.fx, 0.0, intrinsics.cx, 0.0, intrinsics.fy, intrinsics.cy, 0.0, 0.0, 1.0]
            writer.write_message(camera_info_topic or default_camera_info_topic(depth_topic),
                                 writer.register_msgdef("sensor_msgs/msg/CameraInfo", CAMERA_INFO_MSGDEF),
                                 {"header": header(stamps[0]), "height": intrinsics.height, "width": intrinsics.width,
                                  "distortion_model": "plumb_bob", "d": [0.0] * 5, "k": k,
                                  "r": [1.0, 0, 0, 0, 1.0, 0, 0, 0, 1.0],
                                  "p": k[:3] + [0.0] + k[3:6] + [0.0] + k[6:] + [0.0]},
                                 log_time=stamps[0])
        for sequence, (ns, depth) in enumerate(zip(stamps, depths, strict=True)):
            pixels = _encoded(depth, kind, units)
            writer.write_message(depth_topic, image_schema,
                                 {"header": header(ns), "height": pixels.shape[0], "width": pixels.shape[1],
                                  "encoding": encoding, "is_bigendian": 0, "step": pixels.strides[0],
                                  "data": pixels.tobytes()},
                                 log_time=ns, sequence=sequence)
