"""``workbench._compiled``: one signature per kernel, whoever calls it with what."""

from __future__ import annotations

import ast
import json
import os
import shutil
import subprocess
import sys
import textwrap
import threading
from pathlib import Path

import numpy as np
import pytest
from numba.core import types

import workbench
from workbench import _compiled, _dispatchers
from workbench._compiled import entry_point, helper, interpreted, source_digest

#: [rad] the Python source of a kernel against its compiled code (libm, FMA).
ATOL_INTERPRETED = 1e-12


@helper(forceinline=True)
def _scaled(x, k):
    return x * k


@entry_point(outputs=("out",))
def _fill(values, scale: float, out):
    for i in range(values.shape[0]):
        out[i] = _scaled(values[i], scale)
    return out.shape[0]


@helper()
def _entry(values, i):
    return values[i]


@entry_point()
def _total(values, twice: bool) -> float:
    acc = _entry(values, 0) + _entry(values, 1)  # literal indices: one compile
    for i in range(2, values.shape[0]):
        acc += values[i]
    return 2.0 * acc if twice else acc


@entry_point(outputs=("out",))
def _fill_twice(values, out):
    # a nested call with a writable array, a literal int and a literal bool
    _fill(values, 2, out)
    return _total(out, True)


@entry_point(outputs=("out",), vectorize=True)
def _halves(values, out):
    for i in range(out.shape[0]):  # unsigned indices, as the vectorised kernels
        out[np.uint64(i)] = 0.5 * values[np.uint64(i)]


def test_one_signature_whatever_the_arrays_and_scalars() -> None:
    out = np.empty(3)
    readonly = np.arange(3.0)
    readonly.setflags(write=False)
    strided = np.repeat(np.arange(3.0), 2)[::2]
    fortran_row = np.asfortranarray(np.tile(np.arange(3.0), (2, 1)))[0]
    for values in (np.arange(3.0), readonly, strided, fortran_row):
        for scale in (2, 2.0, np.float32(2.0)):  # an int first: still float64
            assert _fill(values, scale, out) == 3
            np.testing.assert_array_equal(out, [0.0, 2.0, 4.0])
    assert _fill_twice(np.arange(3.0), out) == 12.0
    assert _total(readonly, False) == 3.0
    for kernel in (_fill, _total):
        (signature,) = kernel.signatures
        assert signature[0] == types.Array(types.float64, 1, "A", readonly=True)
    writable = types.Array(types.float64, 1, "C")
    assert _fill.signatures[0][1:] == (types.float64, writable)
    assert _total.signatures[0][1] == types.boolean


@helper()
def _pick(values, i):
    return values[i]


def test_helpers_compile_constant_arguments_as_plain_types() -> None:
    array = types.Array(types.float64, 1, "C")
    for index in (types.literal(0), types.literal(1), types.int64):
        _pick.compile((array, index))  # (or loads it from the cache)
    assert _pick.signatures == [(array, types.int64)]


_RECORD = np.dtype([("scale", "f8"), ("shift", "f8", 2)], align=True)


@helper()
def _ratio(record, x):
    return x / record.scale + record.shift[1]  # x / 0.0 is inf, as in numpy


@entry_point(outputs=("out",))
def _ratios(records, values, out):
    record = records[0]
    for i in range(values.shape[0]):
        out[i] = _ratio(record, values[i])
    return record.shift[0]


def test_interpreted_runs_the_python_source_with_the_compiled_semantics() -> None:
    """Record fields as attributes, a division by zero gives inf; nothing compiled."""
    records = np.zeros(1, dtype=_RECORD)
    records["scale"], records["shift"] = 0.0, (3.0, 1.0)
    values, out = np.array([1.0, -2.0]), np.empty(2)
    with interpreted():
        assert _ratios(records, values, out) == 3.0
        assert _ratio(records[0], 4.0) == np.inf  # a record from Python
    assert _ratios.signatures == [] and _ratio.signatures == []
    np.testing.assert_array_equal(out, [np.inf, -np.inf])
    compiled = np.empty(2)
    assert _ratios(records, values, compiled) == 3.0  # compiles now
    np.testing.assert_array_equal(compiled, out)
    assert len(_ratios.signatures) == 1


def test_outputs_refuse_readonly_arrays() -> None:
    out = np.empty(3)
    out.setflags(write=False)
    with pytest.raises(TypeError):
        _fill(np.arange(3.0), 1.0, out)


def test_entry_points_take_no_defaults() -> None:
    def with_default(values, check=True):  # pragma: no cover - never compiled
        return check

    with pytest.raises(TypeError, match="no defaults"):
        entry_point()(with_default)
    with pytest.raises(TypeError, match="no parameters"):
        entry_point(outputs=("missing",))(lambda values: values)


def test_workbench_kernels_are_entry_points_or_helpers() -> None:
    from workbench._compiled import _Kernel
    from workbench._dispatchers import _EntryPoint, _Helper
    from workbench.ik import _chain_kernel, _puma_kernel, _ur_kernel, _velocity_kernel
    from workbench.planning import _tracking

    modules = (_chain_kernel, _puma_kernel, _ur_kernel, _velocity_kernel, _tracking)
    for module in modules:
        compiled = [
            value
            for value in vars(module).values()
            if hasattr(value, "py_func") and value.py_func.__module__ == module.__name__
        ]
        assert compiled
        built = [v.dispatcher if isinstance(v, _Kernel) else v for v in compiled]
        assert all(isinstance(value, _EntryPoint | _Helper) for value in built)


_MODULE = """
from workbench._compiled import entry_point

@entry_point()
def kernel(x: float) -> float:
    return x * 3.0
"""

_SCRIPT = """
import sys
from numba.core import event
compiles = []

class Listener(event.Listener):
    def on_start(self, ev):
        compiles.append(ev.data["dispatcher"].py_func.__name__)

    def on_end(self, ev):
        pass

event.register("numba:compile", Listener())
sys.path.insert(0, sys.argv[1])
import lockmodule
assert lockmodule.kernel(2.0) == 6.0
print(len(compiles))
"""


@pytest.mark.slow
@pytest.mark.subprocess
@pytest.mark.skipif(sys.platform == "win32", reason="no file locks on Windows")
def test_processes_sharing_a_cache_compile_an_entry_point_once(tmp_path: Path) -> None:
    (tmp_path / "lockmodule.py").write_text(textwrap.dedent(_MODULE))
    env = dict(os.environ, NUMBA_CACHE_DIR=str(tmp_path / "cache"))
    runs = [
        subprocess.Popen(
            [sys.executable, "-c", _SCRIPT, str(tmp_path)],
            env=env,
            stdout=subprocess.PIPE,
            text=True,
        )
        for _ in range(2)
    ]
    compiles = [int(run.communicate(timeout=120)[0]) for run in runs]
    assert all(run.returncode == 0 for run in runs)
    assert sorted(compiles) == [0, 1]  # the other process loaded it from the cache
    assert list((tmp_path / "cache").rglob("lockmodule.kernel.lock"))


def test_vectorize_sets_llvm_options_only_while_the_kernel_compiles(
    monkeypatch,
) -> None:
    """The assumption budget and the width are set for the compile, then restored."""
    calls: list[str] = []
    monkeypatch.setattr(_dispatchers.llvm, "set_option", lambda _, o: calls.append(o))
    out = np.empty(9)
    _halves(np.arange(9.0), out)
    np.testing.assert_array_equal(out, np.arange(9.0) / 2)
    assert calls == [
        f"-vectorize-scev-check-threshold={_compiled.VECTORIZE_ASSUMPTIONS}",
        f"-force-vector-width={_compiled.VECTOR_WIDTH}",
        "-vectorize-scev-check-threshold=16",  # LLVM's defaults
        "-force-vector-width=0",
    ]
    _halves(np.arange(9.0), out)  # compiled: nothing set again
    assert len(calls) == 4


_PROBE = """
import json
import numpy as np
from workbench import ik, load_robot

robot = load_robot("puma560")
q = np.array([0.3, -0.5, 0.4, 0.2, 0.3, -0.1])  # theta5 = 0.3 rad
solutions = ik.analytic(robot, robot.fk(q))
print(json.dumps({
    "wrist_singular": [s.wrist_singular for s in solutions],
    "q": [s.q.tolist() for s in solutions],
}))
"""


def _edit(path: Path, old: str, new: str) -> None:
    text = path.read_text()
    assert text.count(old) == 1, f"{old!r} not once in {path}"
    path.write_text(text.replace(old, new))


@pytest.mark.slow
@pytest.mark.subprocess
def test_an_edited_callee_or_constant_is_recompiled_not_loaded(tmp_path: Path) -> None:
    """Numba keys its cache on the entry point's own file; ours on all it imports.

    In a copy of the package with a cache of its own: warm the cache, then
    edit a constant the closed form reads (``_puma.WRIST_SINGULAR_TOL``) and a
    helper in another file than the entry point (``_kernel_common``, called
    by ``_puma_kernel.solve_pose``); a fresh process must run the new code.
    """
    package = Path(workbench.__file__).parent
    source = tmp_path / "source"
    ignore = shutil.ignore_patterns("__pycache__")
    shutil.copytree(package, source / "workbench", ignore=ignore)
    if (package.parent / "urdf").is_dir():  # a source checkout
        shutil.copytree(package.parent / "urdf", source / "urdf", ignore=ignore)
    env = dict(
        os.environ,
        PYTHONPATH=str(source),
        NUMBA_CACHE_DIR=str(tmp_path / "cache"),
        WORKBENCH_PROGRESS="0",
    )

    def solve() -> dict[str, list]:
        done = subprocess.run(
            [sys.executable, "-c", _PROBE],
            cwd=tmp_path,  # not the checkout: the copy is imported
            env=env,
            capture_output=True,
            text=True,
            timeout=300,
        )
        assert done.returncode == 0, done.stderr
        return json.loads(done.stdout)

    before = solve()  # compiles, fills the cache
    assert not any(before["wrist_singular"])
    ik = source / "workbench" / "ik"
    _edit(ik / "_puma.py", "WRIST_SINGULAR_TOL = 1e-10", "WRIST_SINGULAR_TOL = 1.0")
    assert all(solve()["wrist_singular"])  # |sin 0.3| <= 1.0
    _edit(ik / "_puma.py", "WRIST_SINGULAR_TOL = 1.0", "WRIST_SINGULAR_TOL = 1e-10")
    assert solve() == before  # the first entries again
    _edit(
        ik / "_kernel_common.py",
        "math.atan2(y[slot], x[slot])",
        "-math.atan2(y[slot], x[slot])",
    )
    after = solve()
    assert not any(after["wrist_singular"])
    assert after["q"] != before["q"]


def test_source_digest_covers_the_import_closure() -> None:
    """A kernel module's digest covers what it imports, directly or not."""
    digest = source_digest("workbench.ik._puma_kernel")
    assert len(digest) == 64
    closure = set(_compiled._closure("workbench.ik._puma_kernel"))
    assert {
        "workbench.ik._puma_kernel",
        "workbench.ik._kernel_common",  # a helper module
        "workbench.ik._puma",  # constants
        "workbench.poses.rigid",  # RIGIDITY_TOL, through workbench.poses
        "workbench._compiled",
    } <= closure
    assert "workbench.cli" not in closure  # only what it imports


def test_the_import_scan_finds_every_import_the_syntax_tree_has() -> None:
    """Parsing import lines alone misses none of a whole module's imports."""
    package = Path(workbench.__file__).parent
    for file in package.rglob("*.py"):
        parts = file.relative_to(package.parent).with_suffix("").parts
        name = ".".join(parts[:-1] if parts[-1] == "__init__" else parts)
        source = file.read_bytes()
        imports = {
            ast.dump(node)
            for node in ast.walk(ast.parse(source))
            if isinstance(node, ast.Import | ast.ImportFrom)
        }
        found = {ast.dump(node) for node in _compiled._import_statements(source)}
        assert imports <= found, name


@pytest.mark.subprocess
def test_a_kernel_loaded_from_the_cache_then_another_compiled(tmp_path: Path) -> None:
    """A cache load initialises only Numba's runtime; a later compile still works.

    The first process compiles ``triple``; the second loads it (no compile),
    calls it with an int (converted to its float parameter, with Numba's rules
    of conversion) and compiles ``halve``.
    """
    (tmp_path / "twokernels.py").write_text(_TWO_KERNELS)
    env = dict(os.environ, NUMBA_CACHE_DIR=str(tmp_path / "cache"))
    env["WORKBENCH_PROGRESS"] = "0"
    head = "import sys; sys.path.insert(0, sys.argv[1]); import twokernels; "
    for script in (
        "print(twokernels.triple(2.0))",
        "print(twokernels.triple(2), twokernels.halve(3.0), "
        "len(twokernels.halve.signatures))",
    ):
        done = subprocess.run(
            [sys.executable, "-c", head + script, str(tmp_path)],
            env=env,
            capture_output=True,
            text=True,
            timeout=120,
        )
        assert done.returncode == 0, done.stderr
    assert done.stdout == "6.0 1.5 1\n"


_TWO_KERNELS = """
\"\"\"Two kernels: a test module.\"\"\"
from workbench._compiled import entry_point

@entry_point()
def triple(x: float) -> float:
    return x * 3.0

@entry_point()
def halve(x: float) -> float:
    return x / 2.0
"""


@pytest.mark.slow
@pytest.mark.subprocess
def test_the_first_compile_of_a_process_is_said_once_on_stderr(tmp_path: Path) -> None:
    """One line for two compiles; none once cached, none with progress off."""
    (tmp_path / "twokernels.py").write_text(_TWO_KERNELS)
    script = (
        "import sys; sys.path.insert(0, sys.argv[1]); import twokernels; "
        "print(twokernels.triple(2.0) + twokernels.halve(2.0))"
    )
    env = dict(os.environ, NUMBA_CACHE_DIR=str(tmp_path / "cache"))
    env.pop("WORKBENCH_PROGRESS", None)

    def stderr(**extra: str) -> str:
        done = subprocess.run(
            [sys.executable, "-c", script, str(tmp_path)],
            env=dict(env, **extra),
            capture_output=True,
            text=True,
            timeout=120,
        )
        assert done.returncode == 0 and done.stdout == "7.0\n", done.stderr
        return done.stderr

    first = stderr()
    assert first == (
        "workbench: "
        + _compiled.COMPILING.format(what="twokernels.triple, two kernels")
        + "\n"
    )
    assert stderr() == ""  # loaded from the cache
    assert stderr(NUMBA_CACHE_DIR=str(tmp_path / "other"), WORKBENCH_PROGRESS="0") == ""


_STRIDED_FIRST = """
import sys
import numpy as np
from workbench._compiled import entry_point


@entry_point(contiguous=("x",))
def total(x) -> float:
    s = 0.0
    for i in range(x.shape[0]):
        s += x[i]
    return s


strided = np.arange(20.0)[::2]
for call in range(2):
    try:
        print(total(strided))
    except TypeError as error:
        print(f"TypeError: {error}")
print(total(np.ascontiguousarray(strided)))
"""


@pytest.mark.slow
@pytest.mark.subprocess
def test_a_strided_array_is_refused_where_layout_c_is_declared(tmp_path: Path) -> None:
    """Also on the call that compiles: Numba hands that call's own arguments on.

    The signature says layout "C"; a first call with a strided array would run
    on it as if it were contiguous (here the sum of the wrong ten numbers).
    """
    (tmp_path / "strided.py").write_text(_STRIDED_FIRST)
    done = subprocess.run(
        [sys.executable, str(tmp_path / "strided.py")],
        env=dict(os.environ, NUMBA_CACHE_DIR=str(tmp_path / "cache")),
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert done.returncode == 0, done.stderr
    first, second, contiguous = done.stdout.splitlines()
    assert first == "TypeError: total: x must be C-contiguous arrays"
    assert second.startswith("TypeError: No matching definition")
    assert contiguous == "90.0"


def test_compile_in_background_runs_python_until_the_thread_is_done() -> None:
    """True while the thread runs, for at most PYTHON_CALLS calls; then it waits."""
    release, ran = threading.Event(), []

    def warm_up() -> None:
        ran.append(_compiled.compile_in_background(key, warm_up))  # its own thread
        release.wait(timeout=60)

    key = ("test", "held")
    assert _compiled.compile_in_background(key, warm_up)
    with interpreted():  # the call runs as Python anyway
        assert not _compiled.compile_in_background(key, warm_up)
    for _ in range(_compiled.PYTHON_CALLS - 1):
        assert _compiled.compile_in_background(key, warm_up)
    threading.Timer(0.2, release.set).start()
    assert not _compiled.compile_in_background(key, warm_up)  # waited
    assert release.is_set() and ran == [False]
    assert not _compiled.compile_in_background(key, warm_up)


def test_compile_in_background_swallows_the_warm_up_error() -> None:
    """A failing warm-up ends its thread; the caller's own call raises."""

    def warm_up() -> None:
        raise RuntimeError("no compile")

    key = ("test", "failing")
    _compiled.compile_in_background(key, warm_up)
    _compiled.wait_for_background()
    assert not _compiled.compile_in_background(key, warm_up)


_FIRST_SOLVE = """
import sys, threading
import numpy as np
from workbench import load_robot
from workbench._compiled import PYTHON_CALLS, is_compiled, wait_for_background
from workbench.ik import analytic, get_solver
from workbench.ik import _puma_kernel

robot = load_robot("puma560")
rng = np.random.default_rng(3)
poses = [robot.fk(rng.uniform(robot.lower, robot.upper)).homogeneous for _ in range(3)]
first = [analytic(robot, pose).q for pose in poses]
assert not is_compiled(_puma_kernel.solve_pose)  # the Python source answered
threads = [t.name for t in threading.enumerate() if t.name.startswith("workbench")]
assert threads, threading.enumerate()
for _ in range(PYTHON_CALLS):  # the last of them waits for the compile
    analytic(robot, poses[0])
assert is_compiled(_puma_kernel.solve_pose)
assert not any(t.is_alive() for t in threading.enumerate() if t.name in threads)
later = [analytic(robot, pose).q for pose in poses]
solver = get_solver(robot)
assert solver._solve_pose != solver._first_solve_pose  # the compiled entry now
np.savez(sys.argv[1], first=np.array(first), later=np.array(later))
"""


@pytest.mark.slow
@pytest.mark.subprocess
def test_the_first_solve_runs_as_python_while_its_kernels_compile(
    tmp_path: Path,
) -> None:
    """Empty cache: ``ik.analytic`` answers at once, the compile goes on behind.

    The first calls run the Python source (nothing compiled when they return,
    a compile thread alive), the same answers as the compiled code after it;
    the notice says the compile runs in the background; the cache is written
    (a second process says nothing).
    """
    script = tmp_path / "first_solve.py"
    script.write_text(_FIRST_SOLVE)
    env = dict(os.environ, NUMBA_CACHE_DIR=str(tmp_path / "cache"))
    env.pop("WORKBENCH_PROGRESS", None)

    def run() -> str:
        done = subprocess.run(
            [sys.executable, str(script), str(tmp_path / "q.npz")],
            env=env,
            capture_output=True,
            text=True,
            timeout=600,
            cwd=Path(__file__).parents[1],
        )
        assert done.returncode == 0, done.stderr
        return done.stderr

    said = run()
    assert said.startswith("workbench: compiling the Numba kernels"), said
    assert said.rstrip("\n").endswith(_compiled.IN_BACKGROUND), said
    q = np.load(tmp_path / "q.npz")
    np.testing.assert_allclose(q["first"], q["later"], rtol=0, atol=ATOL_INTERPRETED)
    assert run() == ""  # loaded from the cache the thread wrote
