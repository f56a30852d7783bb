"""The schedules a scene sets, checked for what they imply (times in seconds).

Every float key that sets a schedule is refused with a SceneError naming it when it is
subnormal (below the smallest normal float, 2.2e-308 s: no run resolves such a time; a derived
interval can underflow to that or to 0), when it is an interval too small to advance the time
it applies at (t + interval == t), or when it implies more outputs than any run can hold (the
count over time.end, or time.max_steps + 1 when that is fewer: outputs are written at most
once a step). The frame datasets are sized by this count before the first step.
"""

import sys

from pdfem.scene.values import SceneError, show

# Most outputs an interval may imply over time.end: frames hold the whole state (datasets
# allocated up front); samples are rows kept on rank 0; a checkpoint is a file written
MAX_COUNT = {"interval": (10**6, "frames"), "energy_interval": (10**7, "energy samples"),
             "gauge_interval": (10**7, "gauge samples"),
             "checkpoint_interval": (10**6, "checkpoints")}
# Where a derived interval comes from (the schema's defaults)
DERIVED = {"interval": "time.end / 20", "energy_interval": "output.interval / 10",
           "gauge_interval": "output.energy_interval / 10"}


def _normal(path, value, how=""):
    """SceneError unless value is 0 or a normal float; how: where a derived value comes from."""
    if value != 0.0 and abs(value) < sys.float_info.min:
        raise SceneError(path, f"{show(value)} s{how} is subnormal, below "
                         f"{sys.float_info.min:.3g} s: no run resolves such a time")


def _advances(path, interval, at, where):
    """SceneError unless ``at`` + interval > at (the interval moves the time it applies at)."""
    if not at + interval > at:
        raise SceneError(path, f"{show(interval)} s is below the smallest advance of the time "
                         f"at {where} = {show(at)} s")


def check_schedules(r, given_output):
    """The schedules of the resolved scene r (module docstring); given_output: the keys the
    scene's [output] table gave (the others are derived)."""
    end = r["time"]["end"]
    _normal("time.end", end)
    o = r["output"]
    for key, (limit, what) in MAX_COUNT.items():
        path = f"output.{key}"
        iv = o[key]
        if key == "checkpoint_interval" and iv == 0.0:
            continue
        # The schema checks a given interval; a derived one (the others) may underflow
        how = "" if key in given_output else f" (from {DERIVED[key]})"
        if not iv > 0.0:
            raise SceneError(path, f"{show(iv)} s{how} must be > 0")
        _normal(path, iv, how)
        _advances(path, iv, end, "time.end")
        count = end / iv
        if r["time"]["max_steps"]:
            count = min(count, r["time"]["max_steps"] + 1)
        if count > limit:
            raise SceneError(path, f"{show(iv)} s{how} over time.end = {show(end)} s implies "
                             f"{count:.3g} {what}, more than {limit:.0e}")
    _normal("output.checkpoint_wall", o["checkpoint_wall"])
    for i, bc in enumerate(r["bc"]):
        for key in ("release", "ramp_down"):
            if key in bc:
                _normal(f"bc[{i}].{key}", bc[key])
        # A ramp that starts within the run must move the time it starts at
        if bc.get("ramp_down", 0.0) > 0.0 and bc["release"] - bc["ramp_down"] <= end:
            _advances(f"bc[{i}].ramp_down", bc["ramp_down"], bc["release"] - bc["ramp_down"],
                      f"bc[{i}].release - ramp_down")
    if "prepare" in r:
        _normal("prepare.phase_time", r["prepare"]["phase_time"])
