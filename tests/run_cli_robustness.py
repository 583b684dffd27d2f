"""The command line's contract at scale: hundreds of bad inputs and interrupts.

    python -m tests.run_cli_robustness [--cases 300] [--interrupts 200]
        [--map-interrupts 50]

Run by hand (minutes, not part of the suite). First ``--cases`` draws of each
input class of ``tests/_cli_fuzz.py`` (the ``workspace`` classes included),
run in-process: the exit codes, the tracebacks, the failures with more than
one line on stderr and the failed runs that changed a file (all but the exit
codes must be 0). Then ``--interrupts`` runs each of ``workbench demo``,
``workbench plan --csv``, ``workspace view`` and ``workspace report``
(``tests/_interrupts.py``), stopped by SIGINT or SIGKILL after a random delay:
how many outputs were absent, old, complete or truncated (must be 0), the exit
codes, the demo's workers still alive 1 s after a kill (must be 0) and the
temporary files a kill -9 left (removed by the next write of that file).
``--startup`` more SIGINTs land in the first 0.15 s, Python's own start.
``--map-interrupts`` runs of ``workspace map`` are stopped the same way and
then resumed: the map is never half-written and the resumed one is bitwise the
uninterrupted one ("resumed equal" must be all of them).
"""

from __future__ import annotations

import argparse
import tempfile
import time
from collections import Counter
from pathlib import Path

import numpy as np
from hypothesis import HealthCheck, given, settings
from hypothesis.strategies import SearchStrategy

from tests._cli_fuzz import (
    CLASSES,
    WORKSPACE_CLASSES,
    contract_violations,
    run_case,
    write_inputs,
)
from tests._interrupts import (
    COMMANDS,
    Tally,
    interrupt_map_once,
    interrupt_once,
    map_reference,
    run_reference,
)

MIN_DELAY = 0.15  # [s] as tests/test_cli_interrupts.py
#: [s] about a whole run of each (warm cache)
MAX_DELAY = {
    "demo": 2.5,
    "plan": 5.0,
    "workspace view": 1.8,
    "workspace report": 2.5,
    "workspace map": 3.5,
}


def _fuzz_class(
    name: str, strategy: SearchStrategy[tuple[list[str], bytes]], cases: int
) -> tuple[Counter[int], Counter[str]]:
    """Exit codes and contract violations (by kind) of ``cases`` draws."""
    codes: Counter[int] = Counter()
    counts: Counter[str] = Counter()

    @settings(
        max_examples=cases,
        database=None,
        suppress_health_check=list(HealthCheck),
        deadline=None,
    )
    @given(case=strategy)
    def run(case: tuple[list[str], bytes]) -> None:
        argv, bad = case
        with tempfile.TemporaryDirectory() as folder:
            write_inputs(Path(folder), workspace=name in WORKSPACE_CLASSES)
            outcome = run_case(argv, Path(folder), bad)
        codes[outcome.code] += 1
        for problem in contract_violations(outcome):
            key = problem.split()[0] if "line" not in problem else ">1 line"
            counts[key] += 1
            print(f"  {name}: {problem}: {argv}")

    run()
    return codes, counts


def fuzz(cases: int) -> None:
    """Print one row per input class."""
    print(f"{'class':<20}{'cases':>7}{'exit 0':>8}{'exit 2':>8}{'exit 3':>8}"
          f"{'other':>7}{'traceback':>11}{'>1 line':>9}{'changed':>9}")  # fmt: skip
    for name, strategy in {**CLASSES, **WORKSPACE_CLASSES}.items():
        codes, counts = _fuzz_class(name, strategy, cases)
        other = sum(n for code, n in codes.items() if code not in (0, 2, 3))
        print(
            f"{name:<20}{sum(codes.values()):>7}{codes[0]:>8}{codes[2]:>8}"
            f"{codes[3]:>8}{other:>7}{counts['traceback']:>11}"
            f"{counts['>1 line']:>9}{counts['failed']:>9}"
        )


def map_interrupts(count: int, seed: int) -> None:
    """Print one row for ``workspace map`` stopped and resumed ``count`` times."""
    rng = np.random.default_rng(seed)
    tally = Tally()
    with tempfile.TemporaryDirectory() as folder:
        reference = map_reference(Path(folder))
        start = time.perf_counter()
        for _ in range(count):
            interrupt_map_once(
                Path(folder), reference, rng, tally,
                max_delay=MAX_DELAY["workspace map"], min_delay=MIN_DELAY,
            )  # fmt: skip
    files = tally.files
    exits = ", ".join(f"{code}: {n}" for code, n in sorted(tally.exits.items()))
    sent = ", ".join(f"{sig} {n}" for sig, n in sorted(tally.signals.items()))
    print(f"\n{'command':<16}{'runs':>6}{'absent':>8}{'complete':>10}"
          f"{'truncated':>11}{'resumed equal':>15}{'traceback':>11}"
          "  exit codes")  # fmt: skip
    print(
        f"{'workspace map':<16}{tally.runs:>6}{files['absent']:>8}"
        f"{files['complete']:>10}{files['truncated']:>11}"
        f"{files['resumed equal']:>15}{tally.tracebacks:>11}  {exits}"
        f"  ({sent}; {time.perf_counter() - start:.0f} s)"
    )
    for problem in tally.problems:
        print(f"  {problem}")


def interrupts(count: int, startup: int, seed: int) -> None:
    """Print one row per command (and one for the start-up window)."""
    rng = np.random.default_rng(seed)
    print(f"\n{'command':<16}{'runs':>6}{'absent':>8}{'old':>6}{'complete':>10}"
          f"{'truncated':>11}{'orphans':>9}{'temp left':>11}{'traceback':>11}"
          "  exit codes")  # fmt: skip
    rows = [(name, count, MIN_DELAY, MAX_DELAY[name]) for name in COMMANDS if count]
    if startup:
        rows.append(("demo", startup, 0.0, MIN_DELAY))
    for name, runs, low, high in rows:
        tally = Tally()
        with tempfile.TemporaryDirectory() as folder:
            reference = run_reference(name, Path(folder))
            start = time.perf_counter()
            for _ in range(runs):
                interrupt_once(
                    name, Path(folder), reference, rng, tally,
                    max_delay=high, min_delay=low,
                )  # fmt: skip
        label = name if low > 0 else f"{name} <{MIN_DELAY:g} s"
        exits = ", ".join(f"{code}: {n}" for code, n in sorted(tally.exits.items()))
        sent = ", ".join(f"{sig} {n}" for sig, n in sorted(tally.signals.items()))
        files = tally.files
        print(
            f"{label:<16}{tally.runs:>6}{files['absent']:>8}{files['old']:>6}"
            f"{files['complete']:>10}{files['truncated']:>11}{tally.orphans:>9}"
            f"{tally.leftover_temporaries:>11}{tally.tracebacks:>11}  {exits}"
            f"  ({sent}; {time.perf_counter() - start:.0f} s)"
        )
        for problem in tally.problems:
            print(f"  {problem}")


def main() -> None:
    """Parse the options and print both tables."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--cases", type=int, default=300, help="draws per class")
    parser.add_argument(
        "--interrupts", type=int, default=200, help="interrupts per command"
    )
    parser.add_argument(
        "--startup", type=int, default=0, help="SIGINTs in the first 0.15 s"
    )
    parser.add_argument(
        "--map-interrupts",
        type=int,
        default=50,
        help="interrupts of workspace map, each resumed",
    )
    parser.add_argument("--seed", type=int, default=1)
    args = parser.parse_args()
    if args.cases:
        fuzz(args.cases)
    if args.interrupts or args.startup:
        interrupts(args.interrupts, args.startup, args.seed)
    if args.map_interrupts:
        map_interrupts(args.map_interrupts, args.seed)


if __name__ == "__main__":
    main()
