"""Bad input for every command, as hypothesis strategies, and one way to run a case.

Used by ``tests/test_cli_fuzz.py`` (a few dozen cases in the suite) and by
``tests/run_cli_robustness.py`` (hundreds, with a table). Each case is an argv
for ``workbench.cli.main`` run in a fresh folder holding known files (inputs
and existing outputs); :func:`run_case` returns what the contract is checked
against: the exit code, stdout, stderr and the files that changed.
"""

from __future__ import annotations

import contextlib
import hashlib
import io
import json
import os
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
DH_ROW = {"alpha": 1.5707963267948966, "a": 0.1, "d": 0.2}
#: Contents of an existing output that a failed run must leave as it is.
OLD = "old output, must survive a failed run\n"


def write_inputs(folder: Path) -> None:
    """The files the cases read and the existing outputs they must not change."""
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
    ]
)


def _no_file(argv: list[str]) -> tuple[list[str], bytes]:
    return argv, b""


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
