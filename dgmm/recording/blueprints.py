"""rerun blueprints sent with every recording, so ``rerun FILE.rrd`` opens on the views that matter: the 3D scene
beside the curve that tells how the run went, on the run's own timeline."""
import rerun.blueprint as rrb


def _layout(main, timeline, column_shares=(3, 2)):
    """A blueprint of ``main`` (views side by side) with the time panel on ``timeline`` and the side panels
    collapsed."""
    return rrb.Blueprint(rrb.Horizontal(*main, column_shares=list(column_shares)),
                         rrb.BlueprintPanel(state="collapsed"), rrb.SelectionPanel(state="collapsed"),
                         rrb.TimePanel(timeline=timeline, state="expanded"))


def fit_blueprint():
    """A fit (:class:`~dgmm.recording.RerunRecorder`): the input and the mixture's ellipsoids in 3D beside the
    bound, on the ``iteration`` timeline."""
    return _layout([rrb.Spatial3DView(name="input and mixture", origin="/", contents=["/input", "/mixture"]),
                    rrb.TimeSeriesView(name="bound", origin="/bound")], "iteration")


def registration_blueprint(trials):
    """Registration trials (:class:`~dgmm.recording.RegistrationRecorder`): one tab per recorded trial, its
    points over the target mixture in 3D, and one plot of every recorded trial's objective, on the
    ``iteration`` timeline.

    Parameters
    ----------
    trials : iterable of int
        The recorded trials.
    """
    scenes = [rrb.Spatial3DView(name=f"trial {index}", origin="/",
                                contents=["/mixture", f"/trial-{index}/**", f"- /trial-{index}/objective"])
              for index in sorted(trials)]
    if not scenes:
        scenes = [rrb.Spatial3DView(name="mixture", origin="/", contents=["/mixture"])]
    objective = rrb.TimeSeriesView(name="objective", origin="/",
                                   contents=[f"/trial-{index}/objective" for index in sorted(trials)])
    return _layout([rrb.Tabs(*scenes), objective], "iteration")


def odometry_blueprint():
    """Visual odometry (:class:`~dgmm.recording.OdometryRecorder`): the camera path over the ground truth with the
    current depth image back-projected at the camera, that depth image, the current frame's mixture (or points)
    in camera coordinates and the seconds per frame, on the ``frame`` timeline."""
    return _layout([rrb.Spatial3DView(name="camera path", origin="/world"),
                    rrb.Vertical(rrb.Spatial2DView(name="depth image", origin="/world/camera/image"),
                                 rrb.Spatial3DView(name="current frame's model", origin="/world/camera",
                                                   contents=["/world/camera/model"]),
                                 rrb.TimeSeriesView(name="seconds per frame", origin="/seconds"))],
                   "frame", column_shares=(1, 1))
