"""Foxglove messages of mixtures, poses and transforms, built with Foxglove's maintained protobuf types
(``foxglove-schemas-protobuf``), so Foxglove draws them with no plugin."""
import numpy as np
from foxglove_schemas_protobuf.Color_pb2 import Color
from foxglove_schemas_protobuf.FrameTransform_pb2 import FrameTransform
from foxglove_schemas_protobuf.KeyValuePair_pb2 import KeyValuePair
from foxglove_schemas_protobuf.Pose_pb2 import Pose
from foxglove_schemas_protobuf.PoseInFrame_pb2 import PoseInFrame
from foxglove_schemas_protobuf.PosesInFrame_pb2 import PosesInFrame
from foxglove_schemas_protobuf.Quaternion_pb2 import Quaternion
from foxglove_schemas_protobuf.SceneEntity_pb2 import SceneEntity
from foxglove_schemas_protobuf.SceneUpdate_pb2 import SceneUpdate
from foxglove_schemas_protobuf.SpherePrimitive_pb2 import SpherePrimitive
from foxglove_schemas_protobuf.Vector3_pb2 import Vector3
from google.protobuf.timestamp_pb2 import Timestamp
from scipy.spatial.transform import Rotation

from dgmm.errors import InputError
from dgmm.recording.ellipsoids import DEFAULT_N_SIGMA, covariance_ellipsoids


def timestamp(ns):
    """``google.protobuf.Timestamp`` (Foxglove's time) from integer nanoseconds."""
    seconds, nanos = divmod(int(ns), 1_000_000_000)
    return Timestamp(seconds=seconds, nanos=nanos)


def _poses(positions, quaternions):
    """Foxglove ``Pose`` messages from positions (n, 3) and quaternions (n, 4) in (x, y, z, w) order."""
    return [Pose(position=Vector3(x=x, y=y, z=z), orientation=Quaternion(x=qx, y=qy, z=qz, w=qw))
            for (x, y, z), (qx, qy, qz, qw) in zip(np.asarray(positions, dtype=np.float64).tolist(),
                                                   np.asarray(quaternions, dtype=np.float64).tolist(), strict=True)]


def ellipsoid_scene_update(means, covariances, *, log_time_ns, entity_id="mixture", frame_id="world",
                           n_sigma=DEFAULT_N_SIGMA, color=(0.2, 0.6, 1.0, 0.5), metadata=None):
    """A ``foxglove.SceneUpdate`` with one entity drawing a mixture's components as ellipsoids.

    Each component is a ``SpherePrimitive`` centred on its mean, oriented by the proper rotation of its
    principal axes, with ``size`` (full diameters) ``2 * n_sigma * sqrt(eigenvalue)``.

    Parameters
    ----------
    means : array-like of shape (n_components, 3)
    covariances : array-like of shape (n_components, 3, 3)
    log_time_ns : int
        Entity timestamp in nanoseconds.
    entity_id : str, default="mixture"
        An entity replaces any earlier one with the same id on the same topic.
    frame_id : str, default="world"
    n_sigma : float, default=2.0
    color : tuple of 4 floats, default=(0.2, 0.6, 1.0, 0.5)
        RGBA in [0, 1].
    metadata : dict, optional
        Shown by Foxglove beside the entity (keys and values as strings).

    Returns
    -------
    message : foxglove_schemas_protobuf.SceneUpdate_pb2.SceneUpdate
    """
    means = np.asarray(means, dtype=np.float64)
    _, half_sizes, quaternions = covariance_ellipsoids(covariances, n_sigma)
    if means.shape != (len(half_sizes), 3):
        raise InputError(f"means must have shape ({len(half_sizes)}, 3), got {means.shape}")
    rgba = Color(**dict(zip("rgba", map(float, color), strict=True)))
    spheres = [SpherePrimitive(pose=pose, size=Vector3(x=x, y=y, z=z), color=rgba)
               for pose, (x, y, z) in zip(_poses(means, quaternions), (2.0 * half_sizes).tolist())]
    entity = SceneEntity(timestamp=timestamp(log_time_ns), frame_id=frame_id, id=entity_id, spheres=spheres,
                         metadata=[KeyValuePair(key=str(key), value=str(value))
                                   for key, value in (metadata or {}).items()])
    return SceneUpdate(entities=[entity])


def poses_in_frame(rotations, translations, *, log_time_ns, frame_id="world"):
    """A ``foxglove.PosesInFrame`` from rigid transforms ``x -> R x + t``.

    Parameters
    ----------
    rotations : array-like of shape (n_poses, 3, 3)
        Proper rotation matrices.
    translations : array-like of shape (n_poses, 3)
    log_time_ns : int
        Message timestamp in nanoseconds.
    frame_id : str, default="world"

    Returns
    -------
    message : foxglove_schemas_protobuf.PosesInFrame_pb2.PosesInFrame
    """
    translations = np.asarray(translations, dtype=np.float64).reshape(-1, 3)
    quaternions = Rotation.from_matrix(np.asarray(rotations, dtype=np.float64).reshape(-1, 3, 3)).as_quat()
    if len(quaternions) != len(translations):
        raise InputError(f"got {len(quaternions)} rotations but {len(translations)} translations")
    return PosesInFrame(timestamp=timestamp(log_time_ns), frame_id=frame_id,
                        poses=_poses(translations, quaternions))


def pose_in_frame(rotation, translation, *, log_time_ns, frame_id="world"):
    """A ``foxglove.PoseInFrame`` of one rigid transform ``x -> R x + t``.

    Parameters
    ----------
    rotation : array-like of shape (3, 3)
    translation : array-like of shape (3,)
    log_time_ns : int
        Message timestamp in nanoseconds.
    frame_id : str, default="world"

    Returns
    -------
    message : foxglove_schemas_protobuf.PoseInFrame_pb2.PoseInFrame
    """
    (pose,) = poses_in_frame([rotation], [translation], log_time_ns=log_time_ns).poses
    return PoseInFrame(timestamp=timestamp(log_time_ns), frame_id=frame_id, pose=pose)


def frame_transform(rotation, translation, *, log_time_ns, parent_frame_id, child_frame_id):
    """A ``foxglove.FrameTransform``: the pose ``x -> R x + t`` of frame ``child_frame_id`` in ``parent_frame_id``
    (a point's child coordinates ``x`` to its parent coordinates), from ``log_time_ns`` on.

    Parameters
    ----------
    rotation : array-like of shape (3, 3)
    translation : array-like of shape (3,)
    log_time_ns : int
    parent_frame_id, child_frame_id : str

    Returns
    -------
    message : foxglove_schemas_protobuf.FrameTransform_pb2.FrameTransform
    """
    pose = pose_in_frame(rotation, translation, log_time_ns=log_time_ns).pose
    return FrameTransform(timestamp=timestamp(log_time_ns), parent_frame_id=parent_frame_id,
                          child_frame_id=child_frame_id, translation=pose.position, rotation=pose.orientation)
