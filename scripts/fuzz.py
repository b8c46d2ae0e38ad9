#!/usr/bin/env python3
"""The long fuzz run of pointscale's public functions (the short one is tests/test_fuzz.py).

    python3 scripts/fuzz.py --minutes 30          # default 30
    python3 scripts/fuzz.py --minutes 5 --only decompose,project --seed 7

Cases come from tests/fuzz_cases.py (hypothesis strategies: mutated saved decompositions,
extreme point sets, parameters of every public function). Each must end in a finite result, a
ValueError or pointscale.Cancelled. The cases run in a worker process, so that a crash (a
segfault, an abort) or a hang (no progress for --hang seconds) is caught and reported with the
case that caused it; the worker is then started again. At the end the run reports how many
cases ran (in all, per minute and per function, with their outcomes) and every failure with a
reproducer:

    cd tests && python3 -c "from fuzz_cases import *; print(run(<case>))"

Exit status 0 when nothing failed, 1 otherwise.
"""
from __future__ import annotations

import argparse
import collections
import json
import os
import random
import subprocess
import sys
import tempfile
import time
import traceback
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
TESTS = ROOT / "tests"


def reproducer(case_repr: str) -> str:
    return f'cd {TESTS} && python3 -c "from fuzz_cases import *; print(run({case_repr}))"'


# ------------------------------------------------------------------------------------ worker


def worker(args) -> None:
    """Runs batches of hypothesis-drawn cases until args.until; writes its state (the case it
    is running, the counts, the failures) to args.state after every case."""
    sys.path.insert(0, str(TESTS))
    import fuzz_cases
    from hypothesis import HealthCheck, Phase, given, seed, settings

    strategies = fuzz_cases.case_strategies(args.scale)
    if args.only:
        strategies = {k: v for k, v in strategies.items() if k in args.only.split(",")}
    cases = fuzz_cases.st.one_of(list(strategies.values()))
    state = {"count": 0, "outcomes": {}, "failures": [], "guarded": [], "current": None, "pid": os.getpid()}

    def save():
        tmp = args.state + ".tmp"
        with open(tmp, "w") as f:
            json.dump(state, f)
        os.replace(tmp, args.state)

    rng = random.Random(args.seed)
    while time.time() < args.until:
        batch_seed = rng.randrange(2**32)
        last = {}

        @seed(batch_seed)
        @settings(max_examples=100, deadline=None, database=None, derandomize=False, print_blob=True,
                  suppress_health_check=list(HealthCheck), phases=[Phase.generate, Phase.shrink])
        @given(case=cases)
        def batch(case):
            if time.time() >= args.until:
                return
            last["case"] = repr(case)
            state["current"] = last["case"]
            save()
            outcome = fuzz_cases.run(case)  # raises fuzz_cases.Failure
            state["count"] += 1
            key = f"{case.function}: {outcome}"
            state["outcomes"][key] = state["outcomes"].get(key, 0) + 1
            if "non-finite" in outcome and len(state["guarded"]) < 10:
                state["guarded"].append(last["case"])
            state["current"] = None

        try:
            batch()
        except Exception as exc:  # a Failure after shrinking: `last` holds the minimal case
            state["failures"].append({"kind": "failure", "seed": batch_seed, "case": last.get("case"),
                                      "error": "".join(traceback.format_exception_only(type(exc), exc)).strip()})
        state["current"] = None
        save()


# ------------------------------------------------------------------------------------ parent


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--minutes", type=float, default=30.0, help="how long to run (default 30)")
    parser.add_argument("--seed", type=int, default=None, help="master seed of the batches (default: random)")
    parser.add_argument("--only", default="", help="comma-separated function names (default: all)")
    parser.add_argument("--scale", type=float, default=1.0, help="point-count scale of the cases")
    parser.add_argument("--hang", type=float, default=300.0, help="seconds one case may run before it counts as a hang")
    parser.add_argument("--worker", action="store_true", help=argparse.SUPPRESS)
    parser.add_argument("--state", help=argparse.SUPPRESS)
    parser.add_argument("--until", type=float, help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.worker:
        worker(args)
        return 0

    master = args.seed if args.seed is not None else random.randrange(2**31)
    print(f"fuzzing pointscale for {args.minutes:g} minutes, seed {master}"
          + (f", only {args.only}" if args.only else ""), flush=True)
    start = time.time()
    until = start + 60.0 * args.minutes
    count = 0
    outcomes: collections.Counter = collections.Counter()
    failures = []
    guarded = []
    restarts = 0
    with tempfile.TemporaryDirectory() as folder:
        state_path = os.path.join(folder, "state.json")
        while time.time() < until:
            if os.path.exists(state_path):
                os.remove(state_path)
            command = [sys.executable, str(Path(__file__).resolve()), "--worker", "--state", state_path,
                       "--until", str(until), "--seed", str(master + restarts), "--scale", str(args.scale),
                       "--only", args.only]
            proc = subprocess.Popen(command, cwd=str(ROOT), stdout=subprocess.DEVNULL, stderr=subprocess.PIPE,
                                    text=True)
            state, seen, seen_at = {}, None, time.time()
            while proc.poll() is None:
                time.sleep(1.0)
                try:
                    with open(state_path) as f:
                        state = json.load(f)
                except (OSError, ValueError):
                    continue
                marker = (state.get("count"), state.get("current"))
                if marker != seen:
                    seen, seen_at = marker, time.time()
                elif state.get("current") and time.time() - seen_at > args.hang:
                    proc.kill()
                    proc.wait()
                    failures.append({"kind": f"hang (no progress in {args.hang:g} s)", "case": state["current"],
                                     "error": ""})
                    print(f"HANG: {state['current']}", flush=True)
                    break
            stderr = proc.stderr.read() if proc.stderr else ""
            try:
                with open(state_path) as f:
                    state = json.load(f)
            except (OSError, ValueError):
                pass
            count += state.get("count", 0)
            outcomes.update(state.get("outcomes", {}))
            guarded += state.get("guarded", [])
            for failure in state.get("failures", []):
                failures.append(failure)
                print(f"FAILURE: {failure['error']}\n  {failure['case']}", flush=True)
            if proc.returncode not in (0, None) and proc.returncode != -9:
                tail = "\n".join(stderr.strip().splitlines()[-5:])
                failures.append({"kind": f"crash (exit status {proc.returncode})", "case": state.get("current"),
                                 "error": tail})
                print(f"CRASH ({proc.returncode}): {state.get('current')}\n{tail}", flush=True)
            restarts += 1
            print(f"  {count} cases after {(time.time() - start) / 60:.1f} min", flush=True)

    minutes = (time.time() - start) / 60.0
    print(f"\n{count} cases in {minutes:.1f} minutes ({count / max(minutes, 1e-9):.0f} per minute), "
          f"{len(failures)} failures, worker started {restarts} times")
    per_function = collections.defaultdict(dict)
    for key, value in outcomes.items():
        function, outcome = key.split(": ")
        per_function[function][outcome] = value
    for function in sorted(per_function):
        print(f"  {function:22s} " + ", ".join(f"{k} {v}" for k, v in sorted(per_function[function].items())))
    for case in guarded[:10]:
        print(f"\nallowed, but worth a look: a ValueError from the last guard (a non-finite result):\n"
              f"  reproduce: {reproducer(case)}")
    for i, failure in enumerate(failures, 1):
        print(f"\nfailure {i}: {failure['kind']}: {failure['error']}")
        if failure.get("case"):
            print(f"  reproduce: {reproducer(failure['case'])}")
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
