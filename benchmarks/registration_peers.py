"""Registration side by side: our P2D, D2D, ICP and CPD against Open3D, small_gicp and probreg, same seeded trials.

The trials are the workflow's own (``dgmm.experiments.trials.make_trials``, root seed 0, Fig 6's protocol): the bunny
res4 (453 source points, ±15° and ±0.05 m per axis) and one Table 1 model in millimetres (Lucy, quadric1000 mesh);
source and target points drawn from a 50,000-point Poisson-disk sample of the mesh the registered mesh comes from,
P2D mixtures (K=100, k-means start, the scaled protocol's covariance floor) fitted as the workflow fits them
(``mesh-kmeans`` to the exact triangles, ``points-kmeans`` to the vertices). Every method starts from the identity
and moves the trial's source:

- ours: P2D with the paper's BFGS and with the Gauss-Newton solver, on both mixtures (all trials); D2D from the
  mesh mixture to a K=100 mixture fitted to the moved source points (fit time not counted), with both solvers;
  the authors' both-ways ICP and rigid CPD (pycpd's algorithm, dgmm.registration.cpd; to the target points);
- peers (optional extra ``pip install -e '.[peers]'``), to the target points, with their defaults except:
  ICP-like methods get a correspondence distance of a quarter of the model's bounding-box diagonal (the trial
  offsets reach 36% of it) and at most 100 iterations; point-to-plane ICP gets target normals from 30 neighbours
  within 5% of the diagonal; small_gicp downsamples at 1% of the diagonal (keeps every point) and VGICP uses
  voxels of 10% (the best of 2, 5, 10 and 25% on 5 bunny trials). A peer that does not import is reported with its error.

Times are per registration, wall and process CPU time, one thread (OMP, BLAS and each peer's own setting),
medians; the machine's load average is printed beside them, because other jobs share the cores.

Run: ``python benchmarks/registration_peers.py [--trials 250] [--peer-trials 20] [--table1-trials 10]
[--output table.md]`` (about 10 minutes on a loaded 2-core machine; GMMReg and GMMTree take seconds per
registration, hence the smaller subsets).
"""
import os

for _variable in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ[_variable] = "1"

import argparse  # noqa: E402
import time  # noqa: E402
from pathlib import Path  # noqa: E402

import numpy as np  # noqa: E402
from threadpoolctl import threadpool_limits  # noqa: E402

from dgmm import registration as reg  # noqa: E402
from dgmm.data import REGISTRY, fetch, load_mesh  # noqa: E402
from dgmm.experiments.sweep import job_seed  # noqa: E402
from dgmm.experiments.trials import bounding_diagonal, fit_mixture, make_trials, protocol_reg_covar  # noqa: E402
from dgmm.meshes import REDUCTIONS  # noqa: E402
from dgmm.mixture import GaussianMixture  # noqa: E402
from dgmm.primitives import Primitives  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
MIRRORS = [ROOT / ".." / "shared" / "data" / "stanford"]
CACHE = Path("~/.cache/dgmm").expanduser()
MIXTURE = dict(n_components=100, max_iter=100, tol=1e-5, reg_covar=1e-6, variant="textbook")  # config.yaml
EXPERIMENTS = {"fig6": ("bunny", "res4"), "table1": ("lucy", "quadric1000")}


# ------------------------------------------------------------------------------------------------ trials
def experiment(model, mesh, n_trials):
    """Mesh, diagonal, trials and P2D mixtures of one (model, mesh), as the workflow builds them."""
    vertices, faces = load_mesh(fetch(REGISTRY[model]["res4" if mesh == "res4" else "full"], MIRRORS, CACHE))
    full = (vertices, faces)
    if mesh != "res4":
        vertices, faces = REDUCTIONS["quadric"](vertices, faces, int(mesh.removeprefix("quadric")))
    dense = REDUCTIONS["poisson"](*full, 50_000)[0]
    diagonal = bounding_diagonal(vertices)
    setups = make_trials(dense, len(vertices), range(n_trials), root_seed=0, key=f"registration/{model}/{mesh}",
                         diagonal=diagonal)
    settings = {**MIXTURE, "reg_covar": protocol_reg_covar(MIXTURE["reg_covar"], diagonal, "scaled")}
    mixtures = {name: fit_mixture(name, vertices, faces, **settings,
                                  seed=job_seed(0, f"registration/{model}/{mesh}/{name}", 0))
                for name in ("mesh-kmeans", "points-kmeans")}
    return diagonal, setups, mixtures


# ----------------------------------------------------------------------------------------------- methods
def ours(mixtures, diagonal):
    """name -> register(setup) -> (rotation, translation) of our methods."""

    def p2d(name, solver):
        return lambda s: reg.register_p2d(s.moved, mixtures[name], solver=solver)

    def d2d(solver):
        def register(s):
            moving = GaussianMixture(MIXTURE["n_components"], max_iter=MIXTURE["max_iter"], tol=MIXTURE["tol"],
                                     reg_covar=MIXTURE["reg_covar"], random_state=s.index).fit(Primitives.from_points(s.moved))
            return lambda: reg.register_d2d(mixtures["mesh-kmeans"], moving, solver=solver)
        return register  # returns the timed call: the moving mixture's fit is not timed

    return {
        "P2D mesh-kmeans, BFGS (paper)": p2d("mesh-kmeans", "bfgs"),
        "P2D mesh-kmeans, Gauss-Newton": p2d("mesh-kmeans", "gauss-newton"),
        "P2D points-kmeans, BFGS (paper)": p2d("points-kmeans", "bfgs"),
        "P2D points-kmeans, Gauss-Newton": p2d("points-kmeans", "gauss-newton"),
        "D2D mesh-kmeans to moved-points GMM, BFGS": d2d("bfgs"),
        "D2D mesh-kmeans to moved-points GMM, Gauss-Newton": d2d("gauss-newton"),
        "ICP both ways (paper's baseline)": lambda s: reg.register_icp(s.moved, s.target),
        "CPD (rigid, pycpd's algorithm)": lambda s: reg.register_cpd(s.moved, s.target),
    }


def _pose(rotation, translation):
    return np.asarray(rotation, dtype=float), np.asarray(translation, dtype=float)


def _probreg(function, **options):
    """A probreg registration read back as the Kabsch fit of the source to its moved source (drops CPD's scale)."""
    def register(s):
        result = function(s.moved, s.target, **options)
        moved = getattr(result, "transformation", result).transform(s.moved)
        return _pose(*reg.kabsch(s.moved, moved))
    return register


def peers(diagonal):
    """name -> register(setup) -> (rotation, translation), or name -> error text for a peer that does not import."""
    distance = diagonal / 4
    methods = {}
    try:
        import open3d as o3d

        o3d.utility.set_verbosity_level(o3d.utility.VerbosityLevel.Error)
        criteria = o3d.pipelines.registration.ICPConvergenceCriteria(max_iteration=100)
        estimators = {
            "Open3D point-to-point ICP": o3d.pipelines.registration.TransformationEstimationPointToPoint(),
            "Open3D point-to-plane ICP": o3d.pipelines.registration.TransformationEstimationPointToPlane(),
        }

        def cloud(points, normals=False):
            pc = o3d.geometry.PointCloud(o3d.utility.Vector3dVector(points))
            if normals:
                pc.estimate_normals(o3d.geometry.KDTreeSearchParamHybrid(radius=0.05 * diagonal, max_nn=30))
            return pc

        def icp(estimator, normals):
            def register(s):
                result = o3d.pipelines.registration.registration_icp(cloud(s.moved), cloud(s.target, normals),
                                                                     distance, np.eye(4), estimator, criteria)
                return _pose(result.transformation[:3, :3], result.transformation[:3, 3])
            return register

        methods["Open3D point-to-point ICP"] = icp(estimators["Open3D point-to-point ICP"], False)
        methods["Open3D point-to-plane ICP"] = icp(estimators["Open3D point-to-plane ICP"], True)

        def gicp(s):
            result = o3d.pipelines.registration.registration_generalized_icp(
                cloud(s.moved), cloud(s.target), distance, np.eye(4),
                o3d.pipelines.registration.TransformationEstimationForGeneralizedICP(), criteria)
            return _pose(result.transformation[:3, :3], result.transformation[:3, 3])

        methods["Open3D generalized ICP"] = gicp
    except Exception as exc:  # a missing or broken peer is reported, not dropped
        methods["Open3D"] = f"{type(exc).__name__}: {exc}"
    try:
        import small_gicp

        def small(kind):
            def register(s):
                result = small_gicp.align(s.target, s.moved, registration_type=kind, num_threads=1,
                                          downsampling_resolution=0.01 * diagonal, voxel_resolution=0.1 * diagonal,
                                          max_correspondence_distance=distance, max_iterations=100)
                return _pose(result.T_target_source[:3, :3], result.T_target_source[:3, 3])
            return register

        methods["small_gicp GICP"] = small("GICP")
        methods["small_gicp VGICP"] = small("VGICP")
    except Exception as exc:
        methods["small_gicp"] = f"{type(exc).__name__}: {exc}"
    try:
        from probreg import cpd, filterreg, gmmtree, l2dist_regs

        methods["probreg CPD (rigid)"] = _probreg(cpd.registration_cpd)
        methods["probreg FilterReg (point-to-point)"] = _probreg(filterreg.registration_filterreg)
        methods["probreg GMMTree"] = _probreg(gmmtree.registration_gmmtree)
        methods["probreg GMMReg (L2, rigid)"] = _probreg(l2dist_regs.registration_gmmreg)
        methods["probreg SVR (L2, rigid)"] = _probreg(l2dist_regs.registration_svr)
    except Exception as exc:
        methods["probreg"] = f"{type(exc).__name__}: {exc}"
    return methods


# ------------------------------------------------------------------------------------------------ runner
def run(register, setups, diagonal):
    """Errors and times of one method over ``setups``; an exception in a trial is reported as the row's note."""
    rows = []
    for s in setups:
        try:
            call = register(s)
            timed = call if callable(call) else None
            wall, cpu = time.perf_counter(), time.process_time()
            result = timed() if timed else call
            wall, cpu = time.perf_counter() - wall, time.process_time() - cpu
        except Exception as exc:
            return rows, f"{type(exc).__name__}: {str(exc).splitlines()[0] if str(exc) else ''}".strip()
        if isinstance(result, reg.Registration):
            result = (result.rotation, result.translation)
        estimate = reg.Registration(*result, 0, wall, 0.0, True, "peer")
        rows.append((*reg.registration_errors(estimate, s.trial, diagonal), wall, cpu))
    return rows, ""


def _timed(register):
    """Wrap a method returning its result directly so that ``run`` times the call itself."""
    return lambda s: (lambda: register(s))


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--trials", type=int, default=250, help="Fig 6 trials for our P2D rows (the paper's 250)")
    parser.add_argument("--peer-trials", type=int, default=20, help="Fig 6 trials for every other row")
    parser.add_argument("--table1-trials", type=int, default=10, help="trials on the millimetre model")
    parser.add_argument("--output", type=Path, help="also write the markdown table here")
    args = parser.parse_args()

    lines = [f"load average at start: {' '.join(f'{x:.2f}' for x in os.getloadavg())}"]
    print(lines[0], flush=True)
    table = ["| experiment | method | trials | rotation error mean / median (°) | translation error mean / median "
             "(% of diagonal) | median ms per registration (wall / CPU) | note |", "|---|---|---|---|---|---|---|"]
    with threadpool_limits(1):
        for name, (model, mesh) in EXPERIMENTS.items():
            n_all = args.trials if name == "fig6" else args.table1_trials
            n_peer = min(n_all, args.peer_trials if name == "fig6" else args.table1_trials)
            diagonal, setups, mixtures = experiment(model, mesh, n_all)
            print(f"{name}: {model}/{mesh}, diagonal {diagonal:.5g}, {len(setups[0].moved)} points", flush=True)
            methods = {key: (value if key.startswith("D2D") else _timed(value))
                       for key, value in ours(mixtures, diagonal).items()}
            methods.update({key: (value if isinstance(value, str) else _timed(value))
                            for key, value in peers(diagonal).items()})
            for method, register in methods.items():
                n = n_all if method.startswith("P2D") else n_peer
                if isinstance(register, str):
                    rows, note = [], f"not available: {register}"
                else:
                    rows, note = run(register, setups[:n], diagonal)
                if rows:
                    a = np.array(rows)
                    cells = (f"{a[:, 0].mean():.3g} / {np.median(a[:, 0]):.3g}",
                             f"{a[:, 1].mean():.3g} / {np.median(a[:, 1]):.3g}",
                             f"{1e3 * np.median(a[:, 2]):.3g} / {1e3 * np.median(a[:, 3]):.3g}")
                else:
                    cells = ("-", "-", "-")
                row = f"| {model} {mesh} | {method} | {len(rows)} | {' | '.join(cells)} | {note} |"
                table.append(row)
                print(row, f"(load {os.getloadavg()[0]:.2f})", flush=True)
    lines.append(f"load average at end: {' '.join(f'{x:.2f}' for x in os.getloadavg())}")
    print(lines[-1])
    text = "\n".join(table + [""] + lines) + "\n"
    print("\n" + text)
    if args.output:
        args.output.write_text(text)


if __name__ == "__main__":
    main()
