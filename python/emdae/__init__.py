"""emdae from Python: scenes, models, runs, comparisons and studies.

    import emdae
    scene = emdae.load("examples/ring_impact.toml", {"time.t_end": 2.0})
    result = emdae.run(scene, scheme="midpoint")
    t, err = result.history["t"], result.history["energy_error"]   # numpy views

The scene reader, the model and the run are the C++ library's (the same calls
the emdae command makes), so a run gives the command line's numbers to the
last digit. docs/python.md describes the module.
"""

import csv as _csv
import json as _json
import math as _math
import os as _os
import shutil as _shutil
import tempfile as _tempfile

from . import _emdae
from ._emdae import (  # noqa: F401  (the module's names)
    ContactSettings,
    Error,
    GeneralizedAlphaSettings,
    IdaSettings,
    InputError,
    Material,
    Mesh,
    Model,
    ModelError,
    NewtonSettings,
    OutputError,
    OutputSettings,
    Result,
    RunSettings,
    Scene,
    SceneError,
    SchemeSettings,
    TimeFunction,
    TimeSettings,
    Tolerances,
    disk_mesh,
    known_schemes,
    material,
    read_gmsh,
    rectangle_mesh,
    ring_mesh,
)

__all__ = [
    "load", "load_text", "run", "compare", "study", "Scene", "Model", "Result",
    "RunSettings", "TimeFunction", "ring_mesh", "rectangle_mesh", "disk_mesh", "read_gmsh",
    "material", "known_schemes", "Error", "SceneError", "ModelError", "InputError",
    "OutputError", "Mesh", "Material", "TimeSettings", "NewtonSettings", "ContactSettings",
    "IdaSettings", "GeneralizedAlphaSettings", "SchemeSettings", "OutputSettings", "Tolerances",
]


# --- overrides ---------------------------------------------------------------------------

def _toml_value(value):
    """A Python value as the TOML text of a --set value."""
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, int):
        return str(value)
    if isinstance(value, float):
        if _math.isnan(value):
            return "nan"
        if _math.isinf(value):
            return "inf" if value > 0 else "-inf"
        return repr(value)  # the shortest text that reads back as the same double
    if isinstance(value, str):
        return value  # as --set: TOML if it is valid TOML, else a plain string
    if isinstance(value, (list, tuple)):
        return "[" + ", ".join(_toml_element(v) for v in value) + "]"
    if hasattr(value, "tolist"):  # numpy arrays and scalars
        return _toml_value(value.tolist())
    raise TypeError(f"cannot give {type(value).__name__} {value!r} as a scene value")


def _toml_element(value):
    if isinstance(value, str):
        return _json.dumps(value)  # a quoted TOML basic string
    return _toml_value(value)


def _assignments(overrides):
    """Overrides as "key=value" assignments: a dict {key: value} (values as
    Python or TOML text), or a list of "key=value" strings as --set takes."""
    if overrides is None:
        return []
    if isinstance(overrides, dict):
        return [f"{k}={_toml_value(v)}" for k, v in overrides.items()]
    if isinstance(overrides, str):
        return [overrides]
    return [str(a) for a in overrides]


# --- scenes ------------------------------------------------------------------------------

def load(path=None, overrides=None):
    """The scene of a TOML file (None: the built-in default scene, the paper's
    ring impact), with overrides applied as `emdae run --set` applies them.
    Raises SceneError with the command line's message (file:line:column, key)."""
    assignments = _assignments(overrides)
    if path is None:
        return _emdae._load_default(assignments)
    return _emdae._load_file(_os.fspath(path), assignments)


def load_text(text, name="<text>", overrides=None):
    """The scene of TOML text; `name` stands for the file in messages."""
    return _emdae._load_text(text, name, _assignments(overrides))


def _scene_with(scene, overrides):
    return scene._with_overrides(_assignments(overrides))


Scene.with_overrides = _scene_with
Scene.with_overrides.__doc__ = "The same scene source with more overrides applied (a new Scene)."


# --- runs --------------------------------------------------------------------------------

def run(what, settings=None, *, scheme=None, dt=None, t_end=None, out_dir=None,
        progress=None, keep_states=True):
    """Runs a Scene or a Model and returns its Result.

    settings: a RunSettings (default: the scene's, or RunSettings() for a
    Model); scheme, dt, t_end: shorthands that change a copy of it.
    out_dir: where history.csv, summary.json, report.html, contact.csv and
    the VTU fields go; None writes nothing.
    progress(p): called at every history row with a dict (step, steps, t,
    t_end, energy_error, newton_iterations, active_contacts; a static
    analysis: its increments, t_end its load_time); returning False ends
    the run (Result.end == "interrupted", what was written is kept); an
    exception it raises ends the run and is raised again once the run's
    output is written. Ctrl-C ends it the same way (KeyboardInterrupt).
    keep_states: keep node positions and velocities at the output times.
    """
    if isinstance(what, Scene):
        base = what.settings if settings is None else settings
    elif isinstance(what, Model):
        base = RunSettings() if settings is None else settings
    else:
        raise TypeError("run() takes an emdae.Scene or an emdae.Model")
    s = base.copy()
    if scheme is not None:
        s.scheme = scheme
    if dt is not None:
        s.time.dt = float(dt)
    if t_end is not None:
        s.time.t_end = float(t_end)
    out = None if out_dir is None else _os.fspath(out_dir)
    if isinstance(what, Scene):
        return _emdae._run_scene(what, s, out, progress, keep_states)
    return _emdae._run_model(what, s, out, progress, keep_states)


def _history(self):
    """Every history column by name: views (no copy) of history_table."""
    table = self.history_table
    return {name: table[:, j] for j, name in enumerate(self.columns)}


def _positions(self, name=None):
    """Positions at the output times: (rows, nodes, dim) for all nodes; for a
    body's name its nodes (rows, body nodes, dim), for a particle's
    (rows, dim). Views of what the run kept (keep_states=True)."""
    return _select(self, self._positions, name)


def _velocities(self, name=None):
    """Velocities at the output times, as positions() selects them."""
    return _select(self, self._velocities, name)


def _select(self, states, name):
    if states is None:
        raise InputError("the run did not keep its states (keep_states=False)")
    if name is None:
        return states
    for body, (offset, count) in self._bodies:
        if body == name:
            return states[:, offset:offset + count, :]
    for particle, node in self._particles:
        if particle == name:
            return states[:, node, :]
    known = [b for b, _ in self._bodies] + [p for p, _ in self._particles]
    raise InputError(f"no body or particle named '{name}' (known: {', '.join(known)})")


def _times(self):
    """The times of the history rows (a view)."""
    return self.history_table[:, 0]


def _contact(self):
    """contact.csv as arrays (pair, node, x, y, gap, pressure, weight, force)
    at the last state; None without contact."""
    return self._contact


Result.history = property(_history)
Result.times = property(_times)
Result.positions = _positions
Result.velocities = _velocities
Result.contact = property(_contact)
Result.__repr__ = lambda self: (
    f"<emdae.Result {self.end}: {self.history_table.shape[0]} rows, status '{self.status}'>")


# --- compare and study -------------------------------------------------------------------

def _scene_source(scene, overrides, folder):
    """The scene file and the overrides a command takes: a path, None (the
    built-in scene), or a Scene (its file, or its text written to `folder`)."""
    extra = _assignments(overrides)
    if scene is None:
        return "", extra
    if isinstance(scene, Scene):
        if scene.builtin:
            return "", list(scene.overrides) + extra
        if scene.path:
            return scene.path, list(scene.overrides) + extra
        path = _os.path.join(folder, "scene.toml")
        with open(path, "w", encoding="utf-8") as f:
            f.write(scene.text)
        return path, list(scene.overrides) + extra
    return _os.fspath(scene), extra


def _check_scene(path, assignments):
    # The scene's own errors as SceneError (the command's message, unchanged).
    if path:
        _emdae._load_file(path, assignments)
    else:
        _emdae._load_default(assignments)


def _command(run_command, out_dir):
    """Runs a command into out_dir (None: a folder in a temporary one). The
    temporary folder (also where a scene's text is written for the command
    to read) is removed by the cleanup returned: (code, err, folder, cleanup)."""
    scratch = _tempfile.mkdtemp(prefix="emdae-")
    work = _os.path.join(scratch, "out") if out_dir is None else _os.fspath(out_dir)
    try:
        code, _out, err = run_command(scratch, work)
    except BaseException:
        _shutil.rmtree(scratch, ignore_errors=True)
        raise
    return code, err, work, lambda: _shutil.rmtree(scratch, ignore_errors=True)


def _raise_bad_input(code, err):
    if code == 2:
        lines = [ln for ln in err.splitlines() if ln.startswith("emdae: error: ")]
        message = lines[-1][len("emdae: error: "):] if lines else err.strip()
        raise InputError(message)


def compare(scene=None, schemes=("em", "midpoint", "ida", "galpha"), *, overrides=None,
            dt=None, t_end=None, out_dir=None, jobs=None):
    """`emdae compare`: the scene run with each scheme. Returns a dict: "runs",
    one row per scheme (scheme, exit_code, message and, when it ran, its
    summary as a dict), "exit_code" (the command's), "out_dir" (None when
    out_dir was None: the runs went to a temporary folder, removed).
    jobs: schemes run at once, each on a thread (None: the hardware
    threads; 1: one after the other); the results do not depend on it.
    Bad input raises SceneError or InputError before anything is written."""
    scheme_list = schemes if isinstance(schemes, str) else ",".join(schemes)
    n_jobs = _jobs(jobs)

    def command(folder, work):
        path, assignments = _scene_source(scene, overrides, folder)
        _check_scene(path, assignments)
        return _emdae._compare(path, scheme_list, _text(dt), _text(t_end), work, assignments,
                               n_jobs)

    code, err, work, cleanup = _command(command, out_dir)
    try:
        _raise_bad_input(code, err)
        runs = []
        for name in [s.strip() for s in scheme_list.split(",") if s.strip()]:
            row = {"scheme": name, "summary": None}
            summary = _os.path.join(work, name, "summary.json")
            if _os.path.exists(summary):
                with open(summary, encoding="utf-8") as f:
                    row["summary"] = _json.load(f)
            runs.append(row)
        return {"runs": runs, "exit_code": code, "messages": err,
                "out_dir": None if out_dir is None else work}
    finally:
        cleanup()


def study(scene=None, schemes=("em", "midpoint", "galpha", "ida"), *, dts=None, tols=None,
          t_end=None, reference_dt=None, times=None, measures=None, reference_check=True,
          overrides=None, out_dir=None, jobs=None):
    """`emdae study`: the scene per scheme over step sizes (ida: tolerances)
    against a fine reference. Returns study.json as a dict (its "runs" hold,
    per run, scheme, dt, tol, error, cpu_seconds, ...), with "table": the
    rows of study.csv as dicts and "exit_code". out_dir and jobs as in
    compare(): the figures but the CPU times do not depend on jobs."""
    n_jobs = _jobs(jobs)

    def command(folder, work):
        path, assignments = _scene_source(scene, overrides, folder)
        _check_scene(path, assignments)
        return _emdae._study(path, schemes if isinstance(schemes, str) else ",".join(schemes),
                             _list(dts), _list(tols), _text(t_end), _text(reference_dt),
                             _list(times), _list(measures), reference_check, work, assignments,
                             n_jobs)

    code, err, work, cleanup = _command(command, out_dir)
    try:
        _raise_bad_input(code, err)
        with open(_os.path.join(work, "study.json"), encoding="utf-8") as f:
            result = _json.load(f)
        with open(_os.path.join(work, "study.csv"), encoding="utf-8", newline="") as f:
            result["table"] = list(_csv.DictReader(f))
        result["exit_code"] = code
        result["messages"] = err
        result["out_dir"] = None if out_dir is None else work
        return result
    finally:
        cleanup()


def _jobs(jobs):
    if jobs is None:
        return 0
    if isinstance(jobs, bool) or not isinstance(jobs, int) or jobs < 1:
        raise InputError(f"jobs: must be a whole number >= 1, received {jobs!r}")
    return jobs


def _text(x):
    return "" if x is None else (x if isinstance(x, str) else repr(float(x)))


def _list(xs):
    if xs is None:
        return None
    if isinstance(xs, str):
        return xs
    return ",".join(x if isinstance(x, str) else repr(float(x)) for x in xs)
