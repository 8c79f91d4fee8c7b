"""The long run of the garbage-input harness (tests/helpers/harness.py): several seeds,
thousands of cases, `clear` run in this process; prints cases per kind, exit codes,
failures (known faults apart from new ones) and time.

    python benchmarks/fuzz.py                          # seeds 1-4, 1400 cases each
    python benchmarks/fuzz.py --seeds 7 --n 5000 --kinds urdf,settings
    python benchmarks/fuzz.py --seed 3 --case 41 --kinds log --keep /tmp/case41   # rebuild one case, run it, keep its files
    python benchmarks/fuzz.py --seed 3 --case 41 --kinds log --keep /tmp/case41 --subprocess   # ... as its own process

A case is made from (seed, index) alone: index i of a run over kinds K is of kind
K[i % len(K)], so `--case` needs the same --kinds the run had (a failure's repro line
says which). Exit status: 0 when no new failure was found, 1 otherwise.
"""

from __future__ import annotations

import argparse
import sys
import time
from collections import Counter
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))

from helpers import harness as H


def _one_case(args: argparse.Namespace, kinds: list[str]) -> int:
    folder = Path(args.keep)
    if folder.exists() and any(folder.iterdir()):
        sys.exit(f"{folder} is not empty; --keep wants an empty or new folder")
    mat = H.Materials()
    try:
        kind = H.kind_of(args.case, kinds)
        case = H.build_case(args.seed, args.case, kind, folder, mat)
        print(f"case {args.case} of seed {args.seed}: kind {kind}, tags {sorted(case.tags)}")
        print("made: " + "; ".join(case.recipe))
        for line in case.command_lines():
            print("cmd:  " + line)
        if args.subprocess:
            for argv in case.runs:
                run = H.run_subprocess(argv)
                print(
                    f"exit {run.code} ({run.seconds:.2f} s)\n--- stderr\n{run.stderr}--- stdout (first 600)\n{run.stdout[:600]}"
                )
            return 0
        found, codes, secs = H.execute_case(case)
        print(f"exits {codes} ({secs:.2f} s); expected {sorted(case.expect) if case.expect else 'any documented'}")
        for problem, code in found:
            known = H.known_fault(case, problem, code)
            print(f"  {'note' if problem.soft else 'FAIL'} {problem.symptom} [{known or 'new'}]: {problem.detail}")
        print(f"files kept in {folder}")
        return 1 if any(not p.soft and not H.known_fault(case, p, c) for p, c in found) else 0
    finally:
        mat.close()


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--seeds", type=int, nargs="*", default=[1, 2, 3, 4])
    ap.add_argument("--seed", type=int, help="one seed (same as --seeds S)")
    ap.add_argument("--n", type=int, default=1400, help="cases per seed")
    ap.add_argument("--kinds", default=",".join(H.KINDS), help=f"comma-separated, of {','.join(H.KINDS)}")
    ap.add_argument("--budget", type=float, default=None, help="seconds per seed; no new case is started past it")
    ap.add_argument("--case", type=int, help="rebuild and run this one case (with --seed and --keep)")
    ap.add_argument("--keep", help="folder for --case's files")
    ap.add_argument("--subprocess", action="store_true", help="--case: run it as its own process instead")
    ap.add_argument("--quiet", action="store_true", help="do not print failures as they are found")
    args = ap.parse_args()
    kinds = [k for k in args.kinds.split(",") if k]
    unknown = set(kinds) - set(H.KINDS)
    if unknown:
        ap.error(f"unknown kinds {sorted(unknown)}; known: {', '.join(H.KINDS)}")
    seeds = [args.seed] if args.seed is not None else args.seeds
    if args.case is not None:
        if args.seed is None or not args.keep:
            ap.error("--case needs --seed and --keep")
        return _one_case(args, kinds)

    mat = H.Materials()
    reports = []
    t0 = time.perf_counter()
    try:
        for seed in seeds:
            report = H.run_cases(
                seed,
                args.n,
                kinds,
                budget_s=args.budget,
                mat=mat,
                progress=None if args.quiet else (lambda line: print("  " + line[:1000], flush=True)),
            )
            print(report.summary(), flush=True)
            reports.append(report)
    finally:
        mat.close()
    wall = time.perf_counter() - t0
    total = sum(r.total for r in reports)
    per_kind: Counter[str] = Counter()
    for r in reports:
        per_kind.update(r.cases)
    failures = [f for r in reports for f in r.failures]
    notes = [f for r in reports for f in r.notes]
    print(f"\n{total} cases over seeds {seeds} in {wall:.1f} s ({total / max(wall, 1e-9):.1f} cases/s)")
    print("cases per kind: " + ", ".join(f"{k} {per_kind[k]}" for k in kinds))
    groups: Counter[tuple[str, str, str]] = Counter((f.known or "new", f.kind, f.symptom) for f in failures)
    print(
        f"failures: {len(failures)} ({sum(1 for f in failures if f.known)} known, {sum(1 for f in failures if not f.known)} new); "
        f"notes: {len(notes)}"
    )
    for (known, kind, symptom), n in sorted(groups.items()):
        label = f"{known}: {H.KNOWN_FAULTS[known]}" if known in H.KNOWN_FAULTS else "NEW"
        print(f"  {n:5d}  {kind:10s} {symptom:18s} {label}")
    shown: set[tuple[str, str, str]] = set()
    new = [f for f in failures if not f.known]
    if new:
        print(f"\nnew failures ({len(new)}{', the first 80' if len(new) > 80 else ''}):")
        for f in new[:80]:
            print("  " + f.line)
    if len(new) < len(failures):
        print("\nknown faults, the first repro of each group:")
        for f in failures:
            key = (f.known or "new", f.kind, f.symptom)
            if f.known and key not in shown:
                shown.add(key)
                print(f"  ({f.known}) " + f.line)
    if notes:
        print("\nnotes (first 5):")
        for f in notes[:5]:
            print("  " + f.line)
    return 1 if any(not f.known for f in failures) else 0


if __name__ == "__main__":
    sys.exit(main())
