"""Bad input for every command, as hypothesis strategies, and one way to run a case.

Used by ``tests/test_cli_fuzz.py`` (a few dozen cases in the suite) and by
``tests/run_cli_robustness.py`` (hundreds, with a table). Each case is an argv
for ``workbench.cli.main`` run in a fresh folder holding known files (inputs
and existing outputs); :func:`run_case` returns what the contract is checked
against: the exit code, stdout, stderr and the files that changed.
"""

from __future__ import annotations

import atexit
import contextlib
import hashlib
import io
import json
import os
import shutil
import tempfile
from dataclasses import dataclass
from pathlib import Path

from hypothesis import strategies as st

from workbench.cli import main

#: Table III of Angeles et al. (pick, place) [deg]: a trajectory within limits.
PICK = ["0", "45", "200", "-100", "30", "10"]
PLACE = ["150", "-100", "-10", "100", "-70", "170"]
PLAN = [
    *("plan", "pick-place", "--robot", "puma560", "--pick-deg", *PICK),
    *("--place-deg", *PLACE, "--duration", "10"),
]
REPORT = "report singularities --robot puma560".split()
URSCRIPT = "export --format urscript --robot ur5 --trajectory traj.csv".split()
#: ``ik`` of the identity orientation at a position still to append (3 numbers).
IK_AT = "ik --robot ur5 --angeles7 0 0 0 1".split()
#: ``ik`` of a seven-axis arm (SRS) at a pose it reaches; options to append.
IK_SEVEN = "ik --robot iiwa14 --xyz-quat-wxyz 0.5 0.1 0.4 0 1 0 0".split()
#: ``view`` of a seven-axis arm at a configuration within its limits.
VIEW_SEVEN = ["view", "--robot", "iiwa14", "--deg", *["10"] * 7, "--html", "o.html"]
DH_ROW = {"alpha": 1.5707963267948966, "a": 0.1, "d": 0.2}
#: Contents of an existing output that a failed run must leave as it is.
OLD = "old output, must survive a failed run\n"


def write_inputs(folder: Path, *, workspace: bool = False) -> None:
    """The files the cases read and the existing outputs they must not change.

    ``workspace``: also the maps and task poses of the ``workspace`` cases
    (:func:`write_workspace_inputs`).
    """
    if workspace:
        write_workspace_inputs(folder)
    (folder / "t.json").write_text(json.dumps({"name": "t", "joints": [DH_ROW] * 6}))
    (folder / "scene.json").write_text(
        json.dumps(
            {
                "objects": [
                    {
                        "name": "b",
                        "shape": "box",
                        "size": [0.1] * 3,
                        "position": [3, 3, 3],
                    }
                ]
            }
        )
    )
    (folder / "traj.csv").write_text(
        "t,q1,q2,q3,q4,q5,q6,qd1,qd2,qd3,qd4,qd5,qd6,qdd1,qdd2,qdd3,qdd4,qdd5,qdd6\n"
        "# samples=2\n" + "0" + ",0" * 18 + "\n" + "1" + ",0" * 18 + "\n"
    )
    (folder / "robot.urdf").write_text((folder / "t.json").read_text())
    (folder / "dir").mkdir(exist_ok=True)
    for name in ("old.csv", "old.png", "old.html", "old.urdf", "old.srdf", "old.txt"):
        (folder / name).write_text(OLD)


# --- workspace inputs --------------------------------------------------------
#: ``workspace map`` of a small coarse map (125 voxels × 8 orientations, < 1 s);
#: the output path follows.
SMALL_MAP = [
    *"workspace map --robot puma560 --resolution 0.4 --orientations 8".split(),
    *("--workers", "1", "--out"),
]
#: ``workspace place`` of a small search (8 candidates) against ``map.zarr``;
#: the task follows.
PLACE_ON_MAP = [
    *"workspace place --robot puma560 --map map.zarr --region 0 0.4 0 0.4".split(),
    *"--resolution 0.2 --yaw-step 90 --top 2".split(),
]
TASK_HEADER = "x,y,z,qx,qy,qz,qw"
#: Damaged or wrong maps: ``notmap.zarr`` a Zarr group of no map, ``nodone.zarr``
#: without its ``done`` flags, ``trunc.zarr`` with truncated chunks,
#: ``m.zarr.partial`` an unfinished build, ``empty.zarr`` an empty folder.
BAD_MAPS = (
    "missing.zarr", "notmap.zarr", "nodone.zarr", "trunc.zarr", "m.zarr.partial",
    "empty.zarr", "dir", "task.csv", "map.zarr/zarr.json",
)  # fmt: skip
_workspace_template: list[Path] = []  # built once per process


def _build_workspace_template() -> Path:
    """A folder with ``map.zarr``, the damaged maps and ``task.csv`` (once)."""
    if _workspace_template:
        return _workspace_template[0]
    folder = Path(tempfile.mkdtemp(prefix="workbench-fuzz-maps-"))
    atexit.register(shutil.rmtree, folder, ignore_errors=True)
    with contextlib.redirect_stdout(io.StringIO()):
        code = main(["-q", *SMALL_MAP, str(folder / "map.zarr")])
    if code != 0:
        raise RuntimeError(f"building the fuzz map failed (exit {code})")
    good = folder / "map.zarr"
    for name in ("notmap.zarr", "nodone.zarr", "trunc.zarr", "m.zarr.partial"):
        shutil.copytree(good, folder / name)
    group = json.loads((good / "zarr.json").read_text())
    group["attributes"] = {}
    (folder / "notmap.zarr" / "zarr.json").write_text(json.dumps(group))
    shutil.rmtree(folder / "nodone.zarr" / "done")
    for chunk in (folder / "trunc.zarr").glob("*/c/**/*"):
        if chunk.is_file():
            chunk.write_bytes(chunk.read_bytes()[:3])
    (folder / "empty.zarr").mkdir()
    (folder / "task.csv").write_text(f"{TASK_HEADER}\n0.5,0.1,0.3,0,0,0,1\n")
    _workspace_template.append(folder)
    return folder


def write_workspace_inputs(folder: Path) -> None:
    """Copy the small map, the damaged maps and ``task.csv`` into ``folder``."""
    shutil.copytree(_build_workspace_template(), folder, dirs_exist_ok=True)


# --- input classes -----------------------------------------------------------
_huge_float = st.one_of(
    st.floats(100_001.0, 1e308, allow_nan=False, allow_infinity=False),
    st.sampled_from(["1e9", "1e300", "-1", "0", "-0.0", "1e308", "inf", "nan"]),
).map(str)
_huge_int = st.one_of(
    st.integers(100_001, 10**30), st.integers(-(10**12), 1), st.just(10**400)
).map(str)

SIZES = st.one_of(
    st.tuples(st.just([*PLAN, "--rate"]), _huge_float),
    st.tuples(st.just(PLAN[:-1]), _huge_float),  # --duration
    st.tuples(st.just([*PLAN, "--n-points"]), _huge_int),
    *(
        st.tuples(st.just([*REPORT, "--out", "r.html", option]), _huge_int)
        for option in ("--grid", "--svd-grid")
    ),
    st.tuples(
        st.just([*URSCRIPT, "--out", "o.script", "--servo-rate"]),
        st.one_of(
            st.floats(1e4 + 1, 1e308, allow_nan=False, allow_infinity=False).map(str),
            st.sampled_from(["0", "-5", "1e8"]),
        ),
    ),
    st.tuples(
        st.just(["fishcut", "--csv", "old.csv", "--seed"]),
        st.integers(-(10**20), -1).map(str),
    ),
    st.tuples(st.just(["fishcut", "--csv", "old.csv", "--servo-rate"]), _huge_float),
    st.tuples(
        st.just(IK_AT),
        st.lists(st.floats(1e7, 1e308).map(str), min_size=3, max_size=3),
    ),
    st.tuples(
        st.just([*IK_SEVEN, "--redundancy"]),
        st.floats(1000.001, 1e308).map(str),
    ),
    st.tuples(
        st.just([*VIEW_SEVEN, "--redundancy-sweep"]),
        st.one_of(st.integers(65, 10**30), st.integers(-(10**12), 0)).map(str),
    ),
).map(lambda pair: [*pair[0], *([pair[1]] if isinstance(pair[1], str) else pair[1])])


#: Output paths that cannot be written, for a command reading ``inputs``.
def _bad_outputs(*inputs: str) -> st.SearchStrategy[str]:
    return st.sampled_from(["nodir/o.csv", "dir", "nodir/deeper/x.html", *inputs])


OUTPUTS = st.one_of(
    _bad_outputs("scene.json").map(
        lambda p: [*PLAN, "--scene", "scene.json", "--csv", p]
    ),
    st.one_of(_bad_outputs(), st.sampled_from(["o.xyz", "o", "o.csv"])).map(
        lambda p: [*PLAN, "--csv", "old.csv", "--plot", p]
    ),
    _bad_outputs("traj.csv").map(
        lambda p: [
            *"report singularities --robot puma560 --trajectory traj.csv --out".split(),
            p,
        ]
    ),
    _bad_outputs("t.json").map(lambda p: ["urdf", "from-dh", "t.json", "--out", p]),
    _bad_outputs("robot.urdf").map(
        lambda p: ["urdf", "srdf", "--robot", "robot.urdf", "--out", p]
    ),
    _bad_outputs("traj.csv").map(
        lambda p: [*"export --format csv --trajectory traj.csv --out".split(), p]
    ),
    _bad_outputs("scene.json").map(
        lambda p: ["view", "--robot", "ur5", "--scene", "scene.json", "--html", p]
    ),
    _bad_outputs("scene.json").map(
        lambda p: [*"fishcut --scene scene.json --csv old.csv --html".split(), p]
    ),
    st.sampled_from(["old.txt", "t.json", "dir/../old.csv"]).map(
        lambda p: ["demo", "--out", p]
    ),
)

_json_values = st.recursive(
    st.one_of(
        st.none(), st.booleans(), st.integers(), st.floats(), st.text(max_size=5)
    ),
    lambda inner: st.one_of(
        st.lists(inner, max_size=3), st.dictionaries(st.text(max_size=4), inner)
    ),
    max_leaves=8,
)


@st.composite
def _malformed_file(draw: st.DrawFn) -> bytes:
    """Bytes of a broken JSON or CSV file."""
    kind = draw(st.sampled_from(["deep", "bigint", "utf8", "json", "names", "rows"]))
    if kind == "deep":
        depth = draw(st.integers(5_000, 200_000))
        return ("[" * depth + "]" * depth).encode()
    if kind == "bigint":
        digits = draw(st.integers(300, 4000))
        return (
            json.dumps({"name": "x", "joints": [DH_ROW] * 5})
            .replace("0.1", "1" + "0" * digits, 1)
            .encode()
        )
    if kind == "utf8":
        return b'{"name": "\xff\xfe", "joints": []}'
    if kind == "names":
        name = draw(st.sampled_from(['a"b<c>&', "link1", "frame0", "x-->y", "-", ""]))
        key = draw(st.sampled_from(["name", "tool_frame"]))
        return json.dumps({"name": "t", "joints": [DH_ROW] * 6, key: name}).encode()
    if kind == "rows":
        field = "1" * draw(st.integers(131_073, 300_000))
        rows = draw(st.integers(0, 5))
        head = (
            "t,q1,q2,q3,q4,q5,q6,qd1,qd2,qd3,qd4,qd5,qd6,qdd1,qdd2,qdd3,qdd4,qdd5,qdd6"
        )
        body = "".join(f"{i}" + ",0" * 18 + "\n" for i in range(rows))
        return f"{head}\n# samples={rows + 3}\n{body}{field}\n".encode()
    return json.dumps(draw(_json_values)).encode()


@st.composite
def _malformed(draw: st.DrawFn) -> tuple[list[str], bytes]:
    data = draw(_malformed_file())
    return draw(
        st.sampled_from(
            [
                ["urdf", "from-dh", "bad.in", "--out", "old.urdf"],
                [*PLAN, "--scene", "bad.in", "--csv", "old.csv"],
                ["view", "--robot", "ur5", "--scene", "bad.in", "--html", "old.html"],
                "view --robot ur5 --trajectory bad.in --html old.html".split(),
                "export --format csv --trajectory bad.in --out old.csv".split(),
                [*REPORT, *"--trajectory bad.in --out old.html".split()],
            ]
        )
    ), data


MALFORMED = _malformed()

NUMBERS = st.lists(
    st.one_of(
        st.floats(-1e3, 1e3, allow_nan=False),
        st.floats(-1e-3, 1e-3, allow_nan=False),
    ),
    min_size=6,
    max_size=6,
).map(lambda q: ["fk", "--robot", "ur5", "--rad", *(repr(x) for x in q)])

FLAGS = st.sampled_from(
    [
        [*PLAN, "--scene", "scene.json", "--no-collision"],
        ["fishcut", "--scene", "scene.json", "--no-collision"],
        "export --format csv --trajectory traj.csv --out o.csv --no-collision".split(),
        [
            *"export --format csv --pick-place --scene scene.json".split(),
            *"--no-collision --out o.csv".split(),
        ],
        ["view", "--robot", "ur5", "--deg", "--html", "o.html"],
        ["urdf", "srdf", "--robot", "ur5", "--json"],
        [*IK_AT, "0.4", "0", "0.4", "--redundancy", "1"],
        [*IK_SEVEN, "--redundancy", "1", "--criterion", "manipulability"],
        [*VIEW_SEVEN, "--ik-branches", "--redundancy-sweep", "3"],
        [*VIEW_SEVEN, "--redundancy", "1"],
        [*VIEW_SEVEN, "--redundancy-sweep", "3", "--branch", "nope"],
    ]
)


def _no_file(argv: list[str]) -> tuple[list[str], bytes]:
    return argv, b""


# --- workspace input classes ------------------------------------------------
def _above(limit: int) -> st.SearchStrategy[str]:
    """Integers outside 1..limit (and one beyond any float), as text."""
    return st.one_of(
        st.integers(limit + 1, 10**30), st.integers(-(10**12), 0), st.just(10**400)
    ).map(str)


#: The small map at ``x.zarr``; an option appended overrides (the last wins).
_SMALL = [*SMALL_MAP, "x.zarr"]
_not_positive = st.sampled_from(["0", "-0.0", "-1", "-1e-300", "nan", "inf", "-inf"])
WORKSPACE_SIZES = st.one_of(
    st.tuples(
        st.just([*_SMALL, "--resolution"]),
        st.one_of(_not_positive, st.sampled_from(["10.000001", "1e308", "1e-5"])),
    ),
    st.tuples(st.just([*_SMALL, "--orientations"]), _above(1_000_000)),
    st.tuples(st.just([*_SMALL, "--samples"]), _above(10**12)),
    st.tuples(st.just([*_SMALL, "--workers"]), _above(4096)),
    st.tuples(st.just([*_SMALL, "--block-voxels"]), _above(1 << 20)),
    st.tuples(
        st.just([*SMALL_MAP, "x.zarr", "--robot", "iiwa14", "--redundancy-samples"]),
        _above(4096),
    ),
    st.tuples(
        st.just([*_SMALL, "--cone", "0", "0", "-1"]),
        st.sampled_from(["0", "-30", "180.0001", "1e308", "nan"]),
    ),
    st.tuples(
        st.just([*PLACE_ON_MAP, "--targets", "task.csv", "--top"]), _above(10_000)
    ),
    st.tuples(
        st.just([*PLACE_ON_MAP, "--targets", "task.csv", "--yaw-step"]),
        st.one_of(_not_positive, st.sampled_from(["360.5", "1e308"])),
    ),
    st.tuples(
        st.just([*PLACE_ON_MAP, "--targets", "task.csv", "--resolution"]),
        st.one_of(_not_positive, st.sampled_from(["10.5", "1e-300", "1e-9"])),
    ),
    st.tuples(
        st.just([*PLACE_ON_MAP, "--targets", "task.csv", "--height"]),
        st.sampled_from(["nan", "inf", "-1e308", "1e300"]),
    ),
    st.tuples(
        st.just([*PLACE_ON_MAP, "--targets", "task.csv", "--region"]),
        st.lists(
            st.one_of(
                st.floats(-1e308, 1e308, allow_nan=False).map(repr),
                st.sampled_from(["nan", "inf", "1e400"]),
            ),
            min_size=4,
            max_size=4,
        ),
    ),
).map(lambda pair: [*pair[0], *([pair[1]] if isinstance(pair[1], str) else pair[1])])

WORKSPACE_OUTPUTS = st.one_of(
    st.sampled_from(
        ["old.csv", "dir", "nodir/m.zarr", "map.zarr", "scene.json", "map.zarr/x.zarr"]
    ).map(lambda p: [*SMALL_MAP, p, "--scene", "scene.json"]),
    st.sampled_from(
        [
            "dir",
            "nodir/v.html",
            "map.zarr",
            "map.zarr/zarr.json",
            "map.zarr/reached/zarr.json",
            "map.zarr/../map.zarr/done/zarr.json",
        ]
    ).map(lambda p: ["workspace", "view", "map.zarr", "--html", p]),
    st.sampled_from(
        ["dir", "nodir/r.html", "map.zarr", "map.zarr/zarr.json", "map.zarr/new.html"]
    ).map(lambda p: ["workspace", "report", "map.zarr", "--out", p]),
)


@st.composite
def _task_csv(draw: st.DrawFn) -> bytes:
    """Bytes of a broken (or valid) task pose CSV."""
    kind = draw(st.sampled_from(["rows", "header", "empty", "huge", "long", "utf8"]))
    if kind == "empty":
        return draw(st.sampled_from([b"", b"\n", f"{TASK_HEADER}\n".encode()]))
    if kind == "utf8":
        return f"{TASK_HEADER}\n".encode() + b"\xff\xfe,0,0,0,0,0,1\n"
    if kind == "huge":
        rows = draw(st.sampled_from([100_001, 400_000]))
        return (f"{TASK_HEADER}\n" + "0.5,0.1,0.3,0,0,0,1\n" * rows).encode()
    if kind == "long":
        field = "1" * draw(st.integers(131_073, 300_000))
        return f"{TASK_HEADER}\n{field},0,0,0,0,0,1\n".encode()
    header = TASK_HEADER
    if kind == "header":
        header = draw(
            st.sampled_from(["x,y,z,qw,qx,qy,qz", "x,y,z", "", "x;y;z;qx;qy;qz;qw",
                             TASK_HEADER + ",extra", "X,Y,Z,QX,QY,QZ,QW"])
        )  # fmt: skip
    number = st.one_of(
        st.floats(-2.0, 2.0, allow_nan=False).map(repr),
        st.sampled_from(["nan", "inf", "-inf", "1e400", "", "x", "0x1p0", "1,5"]),
    )
    rows = draw(st.lists(st.lists(number, min_size=5, max_size=8), max_size=4))
    body = "".join(",".join(row) + "\n" for row in rows)
    return f"{header}\n{body}".encode()


@st.composite
def _workspace_malformed(draw: st.DrawFn) -> tuple[list[str], bytes]:
    if draw(st.booleans()):  # a task CSV
        return [*PLACE_ON_MAP, "--targets", "bad.in"], draw(_task_csv())
    bad_map = draw(st.sampled_from([*BAD_MAPS, "bad.in"]))
    argv = draw(
        st.sampled_from(
            [
                ["workspace", "view", bad_map, "--html", "old.html"],
                ["workspace", "report", bad_map, "--out", "old.html"],
                [*PLACE_ON_MAP, "--map", bad_map,
                 "--targets", "task.csv"],
                [*_SMALL, "--scene", "bad.in"],
            ]
        )
    )  # fmt: skip
    return argv, draw(_malformed_file())


WORKSPACE_FLAGS = st.sampled_from(
    [
        [*_SMALL, "--workers", "2", "--scheduler", "tcp://127.0.0.1:1"],
        [*_SMALL, "--scheduler", "no-port"],
        [*_SMALL, "--scheduler", ""],
        [*_SMALL, "--cone", "0", "0", "0", "30"],
        [*_SMALL, "--cone", "0", "0", "1e-320", "30"],
        [*_SMALL, "--cone", "nan", "0", "1", "30"],
        [*_SMALL, "--samples", "10", "--scene", "scene.json"],
        [*_SMALL, "--redundancy-samples", "3"],
        [*_SMALL, "--robot", "panda", "--samples", "10", "--redundancy-samples", "3"],
        [*PLACE_ON_MAP, "--targets", "task.csv", "--trajectory", "traj.csv"],
        [*PLACE_ON_MAP, "--targets", "task.csv", "--region", "1", "0", "0", "1"],
        [*PLACE_ON_MAP, "--targets", "task.csv", "--region", "0", "1", "1", "0"],
        [
            "workspace",
            "place",
            "--robot",
            "ur5",
            "--map",
            "map.zarr",
            "--targets",
            "task.csv",
        ],
        ["workspace", "view", "map.zarr", "--html", "v.html", "--robot", "ur5"],
        ["workspace", "report", "map.zarr", "--out", "r.html", "--heights"],
        ["workspace", "view", "map.zarr", "--html", "v.html", "--measure", "x"],
        [
            "workspace",
            "map",
            "--robot",
            "puma560",
            "--out",
            "x.zarr",
            "--json",
            "--orientations",
            "8",
            "--cone",
            "0",
            "0",
            "1",
        ],
    ]
)

#: The ``workspace`` input classes (their cases need :func:`write_workspace_inputs`).
WORKSPACE_CLASSES: dict[str, st.SearchStrategy[tuple[list[str], bytes]]] = {
    "workspace output paths": WORKSPACE_OUTPUTS.map(lambda a: (a, b"")),
    "workspace malformed files": _workspace_malformed(),
    "workspace sizes": WORKSPACE_SIZES.map(lambda a: (a, b"")),
    "workspace flags": WORKSPACE_FLAGS.map(lambda a: (a, b"")),
}

#: The input classes, by name: each draws (argv, bytes of ``bad.in``).
CLASSES: dict[str, st.SearchStrategy[tuple[list[str], bytes]]] = {
    "output paths": OUTPUTS.map(_no_file),
    "malformed files": MALFORMED,
    "sizes": SIZES.map(_no_file),
    "numbers": NUMBERS.map(_no_file),
    "contradictory flags": FLAGS.map(_no_file),
}


@dataclass(frozen=True)
class Outcome:
    """What one run of the command line did."""

    code: int
    stdout: str
    stderr: str
    changed: tuple[str, ...]  # existing files whose bytes changed


def snapshot(folder: Path) -> dict[str, str]:
    """SHA-256 of every file in ``folder`` (recursively), by relative path."""
    return {
        str(p.relative_to(folder)): hashlib.sha256(p.read_bytes()).hexdigest()
        for p in sorted(folder.rglob("*"))
        if p.is_file()
    }


def run_case(argv: list[str], folder: Path, bad: bytes = b"") -> Outcome:
    """Run ``workbench -q *argv`` in-process in ``folder``; compare the files after.

    ``bad`` is written to ``folder/bad.in`` first (the malformed file).
    """
    if bad:
        (folder / "bad.in").write_bytes(bad)
    before = snapshot(folder)
    out, err = io.StringIO(), io.StringIO()
    cwd = Path.cwd()
    os.chdir(folder)
    try:
        with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
            code = main(["-q", *argv])
    finally:
        os.chdir(cwd)
    after = snapshot(folder)
    changed = tuple(sorted(k for k in before if after.get(k) != before[k]))
    return Outcome(code, out.getvalue(), err.getvalue(), changed)


def contract_violations(outcome: Outcome) -> list[str]:
    """How ``outcome`` breaks the command-line contract (empty: it keeps it).

    Exit 0, 2 or 3; on a failure one line on stderr and no traceback; a failed
    run (any exit but 0 and 3, whose result is complete: ``plan`` and
    ``fishcut`` write an infeasible trajectory for a look) changes no file.
    """
    problems = []
    if outcome.code not in (0, 2, 3):
        problems.append(f"exit code {outcome.code}")
    if "Traceback" in outcome.stderr:
        problems.append("traceback on stderr")
    if outcome.code != 0 and len(outcome.stderr.splitlines()) != 1:
        problems.append(f"{len(outcome.stderr.splitlines())} lines on stderr")
    if outcome.code not in (0, 3) and outcome.changed:  # exit 3: a complete result
        problems.append(f"failed run changed {', '.join(outcome.changed)}")
    return problems
