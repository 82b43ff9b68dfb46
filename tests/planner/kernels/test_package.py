"""The kernels as compiled code: deterministic, cached per module (or compiled in
each process without a cache), and all loaded by the autopilot's warm-up."""

from __future__ import annotations

import numpy as np
from numpy.testing import assert_array_equal

from conesim.planner import MidlineConfig
from conesim.planner.midline import boundary_cones
from tests.child_process import python
from tests.planner.kernels.helpers import loop_projector, random_cones


def run_child(script: str) -> None:
    """Run ``script`` in a fresh Python process from the repository; it must print "ok"."""
    assert python(script).stdout.strip() == "ok"


def test_kernels_are_deterministic() -> None:
    """Same inputs, same outputs, bit for bit, call after call."""
    rng = np.random.default_rng(28)
    config = MidlineConfig()
    cones = random_cones(rng, 70, closed=True)
    first = boundary_cones(cones, config)
    again = boundary_cones(cones, config)
    assert_array_equal(first[0].points, again[0].points)
    assert first[2] == again[2]
    projector = loop_projector(True)
    points = rng.uniform(-40.0, 40.0, (50, 2))
    a = projector.project_around(points, 20.0, 35.0, 2.0)
    b = projector.project_around(points, 20.0, 35.0, 2.0)
    assert_array_equal(a.offset, b.offset)


def test_import_without_a_writable_cache_directory() -> None:
    """No cache directory numba can write: the planner's (each module of ``kernels``,
    ``kernel_chains``) and the EKF's kernels compile uncached, each module with its warning."""

    script = """
import pkgutil
import warnings
import numba.core.caching as caching

def unwritable(self):
    raise OSError("read-only")

caching._CacheLocator.ensure_cache_path = unwritable  # every locator fails
with warnings.catch_warnings(record=True) as caught:
    warnings.simplefilter("always")
    from conesim.planner import kernels
    from conesim.localization.ekf import kernels as ekf_kernels
import numpy as np
owners = {str(w.message).split(":")[0] for w in caught if "no writable cache" in str(w.message)}
modules = {f"conesim.planner.kernels.{m.name}" for m in pkgutil.iter_modules(kernels.__path__)}
assert len(modules) == 11, modules
expected = modules | {"conesim.planner.kernel_chains", "conesim.localization.ekf.kernels"}
assert owners == expected, caught
assert kernels.arc_length(np.array([[0.0, 0.0], [3.0, 4.0]])).tolist() == [0.0, 5.0]
p = np.array([[1.0, 2.0], [4.0, 3.0]])
assert ekf_kernels.symmetrised(p).tolist() == [[1.0, 3.0], [3.0, 3.0]]
print("ok")
"""
    run_child(script)


def test_building_an_autopilot_loads_every_kernel_the_planning_step_calls() -> None:
    """After ``warm_up_planner`` (in ``Autopilot()``), planning along a winding
    track with the local and the global speed source calls no kernel, and no
    argument types, that the warm-up did not already load (a fresh process)."""

    script = """
import dataclasses, importlib, math, pkgutil
import numpy as np
from numba.core.registry import CPUDispatcher
from conesim.localization.frames import Buffer, TransformStamped
from conesim.tracks.global_path import global_path_from_centreline
from conesim.core.messages import ConeDetections, Header
from conesim.core.pose import Pose2D
from conesim.planner import AutopilotConfig, kernel_chains, kernels
from conesim.planner.autopilot import Autopilot
from conesim.planner.midline import PlanStatus

modules = [kernel_chains] + [importlib.import_module(f"conesim.planner.kernels.{m.name}")
                     for m in pkgutil.iter_modules(kernels.__path__)]

def loaded():
    return {f"{module.__name__}.{k}": len(v.signatures) for module in modules
            for k, v in vars(module).items()
            if isinstance(v, CPUDispatcher) and v.signatures and v.__module__ == module.__name__}

x = np.arange(0.0, 200.0, 0.5)
centre = np.column_stack([x, 4.0 * np.sin(x / 8.0)])
t = np.gradient(centre, axis=0)
t /= np.hypot(t[:, 0], t[:, 1])[:, None]
normal = np.column_stack([-t[:, 1], t[:, 0]])
cones = np.vstack([centre + 1.75 * normal, centre - 1.75 * normal])[::5]
path = global_path_from_centreline(centre, closed=False)
assert not loaded()
pilots = [Autopilot(Buffer(), path)]
after_warm_up = loaded()
assert AutopilotConfig().speed_source == "global"
pilots.append(Autopilot(Buffer(), path, dataclasses.replace(
    AutopilotConfig(), speed_source="local")))
ok = 0
for pilot in pilots:
    for k, i in enumerate(range(10, 300, 15)):
        d = centre[i + 1] - centre[i]
        pose = Pose2D(float(centre[i, 0]), float(centre[i, 1]), math.atan2(d[1], d[0]))
        pilot.buffer.set_transform(
            TransformStamped.from_pose2d("reference", "os_sensor", float(k), pose))
        local = pose.inverse_transform_points(cones)
        local = local[(local[:, 0] > -2.0) & (local[:, 0] < 30.0)]
        local = local[np.argsort(np.hypot(local[:, 0], local[:, 1]))]
        plan = pilot.on_detections(ConeDetections(
            Header(float(k), "os_sensor"), np.column_stack([local, np.zeros(len(local))])))
        ok += plan is not None and plan.status is PlanStatus.OK
assert ok > 30, ok
assert loaded() == after_warm_up, (after_warm_up, loaded())
assert {"profile_limits", "profile_passes", "spline_path", "project_around", "plan_cones",
        "plan_midpoints", "project_window"} <= {k.rsplit(".", 1)[1] for k in loaded()}
print("ok")
"""
    run_child(script)
