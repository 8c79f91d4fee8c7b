"""WAM inverse kinematics: time per pose, success rate and IK starts, for the kinds of
gripper poses the planner asks about, with the new solver and the one it replaced.

Solvers ("who"): new = WamKinematics() as the planner builds it (closed-form elbow test,
damped least squares from the warm start or rest shape for at most 20 iterations, then
the swivel sweep); swp = the same with track_iterations = 0 (the sweep alone: exact
solution nearest the start); old = clearcli/robot/kinematics.py at OLD_REV (damped least
squares from the warm start, then 8 seeds, 150 iterations each).

    .venv/bin/python benchmarks/ik.py            # 2000 / 300 / 200 / 500 poses drawn (a few min)
    .venv/bin/python benchmarks/ik.py --quick    # 400 / 60 / 40 / 200 poses drawn (about 1 min)
    .venv/bin/python benchmarks/ik.py --no-old   # without the replaced solver
    .venv/bin/python benchmarks/ik.py --robot panda [--quick]   # another profile (generic IK)
    .venv/bin/python benchmarks/ik.py --robot all [--quick]     # every profile

With --robot NAME (a profile of `clear robots`, the WAM included through the same
groups) the groups are the profile's, in its base frame with the table's plane where
the default placement puts it (the WAM's 0.346 m below its shoulder; a Panda's or a
UR5e's base stands on it):
 (1)  reachable tool-down: FK of random in-limit configurations whose TCP z axis is within
      5 degrees of straight down, 0.01-0.30 m above the table, 0.25-0.80 m from the base's
      vertical axis. No warm start.
 (2)  in reach, no solution: random orientation, TCP 0-0.90 m from the axis, 0.01-0.30 m
      above the table, the flange within the links' summed lengths of the shoulder (a
      URDF arm; the WAM: passing its reachable()), and no solution from a thorough search
      (48 random starts, 200 iterations of damped least squares each).
 (3)  beyond reach: the TCP 1.2-1.6 m from the shoulder: rejected by reachable().

All poses are T_base_tcp in the WAM's DH frame 0 (the shoulder). The table top is
0.346 m below the shoulder (the default placement stands the WAM's footprint on the table
plane just outside its edge, facing +x). Every random draw has a fixed seed.

Groups:
 (1)  reachable: FK of random joint configurations, uniform within the joint limits
      (rejection sampling), kept when the tool points down at the table (TCP z axis
      within 5 degrees of straight down), with the TCP 0.01-0.30 m above the table,
      0.25-0.90 m from the shoulder's vertical axis and in front of it (x > 0). Each has a
      solution by construction. No warm start.
 (1w) the same poses 5 cm higher, each warm-started from its solver's solution of the
      (1) pose (the planner's grasp -> lift); not solvable by construction.
 (2)  in reach, no solution, top-down near the axis: TCP z straight down, random yaw,
      TCP 0-0.35 m from the shoulder's axis (azimuth within +-90 deg), 0.01-0.30 m above
      the table, and passing the reachable() pre-check.
 (2b) in reach, no solution, any orientation: uniformly random tool orientation, TCP
      0-0.90 m from the axis (azimuth within +-90 deg), 0.01-0.30 m above the table,
      passing reachable(). Many of these pass the elbow's closed-form test, and only the
      swivel sweep rejects them.
      For (2) and (2b) a drawn pose is a member only if neither new/swp, nor old, nor a
      thorough search (damped least squares from 48 random starts, 200 iterations each)
      finds a solution. Poses new or swp solve (checked by FK) are counted as solvable;
      poses only old or the thorough search solve are reported as misses of the new.
 (3)  beyond reach: half top-down, half of random orientation, the TCP 0.95-1.6 m from
      the shoulder's axis, 0.3 m below to 0.3 m above the table: the tool plate is beyond
      the arm's 0.915 m stretch. Timed both for ik() and for the reachable() pre-check.

Columns per group and solver: poses, median and p95 ms per ik() call, success rate, mean
damped least squares starts per pose (the warm start or a seed each: "IK starts") and mean
analytic swivel sweeps per pose. The cache is emptied before every call (it would make
repeats free), and the solvers take turns by blocks of 20 poses (timings on this machine
drift by up to 2x from run to run; the ratio old/new is steadier than either). Every
returned solution is checked (within the joint limits, FK within the tolerances); a
nonzero count is printed as WRONG. The old module is loaded from `git show OLD_REV:...`
beside the current one; --no-old skips it.
"""

from __future__ import annotations

import argparse
import importlib.util
import math
import statistics
import subprocess
import sys
import tempfile
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np

REPO = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(REPO))

from clearcli.robot import wam_kinematics as kin_mod  # noqa: E402

TABLE_Z = -0.346  # table top in the base (shoulder) frame
DOWN = np.diag([1.0, -1.0, -1.0])  # TCP z along -z of the base

Record = tuple[np.ndarray | None, float, int, int, bool]  # q, seconds, starts, sweeps, wrong
BLOCK = 20  # poses per turn of a solver (see run)


# -- poses ---------------------------------------------------------------------------------


# The last commit with the seeded damped-least-squares solver this one replaced.
OLD_REV = "c25499e"


def _rz(t: np.ndarray) -> np.ndarray:
    c, s, z, o = np.cos(t), np.sin(t), np.zeros_like(t), np.ones_like(t)
    return np.stack([np.stack([c, -s, z], -1), np.stack([s, c, z], -1), np.stack([z, z, o], -1)], -2)


def _ry(t: np.ndarray) -> np.ndarray:
    c, s, z, o = np.cos(t), np.sin(t), np.zeros_like(t), np.ones_like(t)
    return np.stack([np.stack([c, z, s], -1), np.stack([z, o, z], -1), np.stack([-s, z, c], -1)], -2)


def _dh_fk_many(q: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Vectorised FK of the DH table (rotations (N,3,3), TCP positions (N,3)); only
    filters the draws: the kept configurations are FK'd again by Pinocchio."""
    R = _rz(q[:, 0]) @ _ry(q[:, 1]) @ _rz(q[:, 2])
    W = R @ np.array([0.045, 0.0, 0.55])
    R = R @ _ry(q[:, 3])
    W = W + R @ np.array([-0.045, 0.0, 0.30])
    R = R @ _rz(q[:, 4]) @ _ry(q[:, 5]) @ _rz(q[:, 6])
    return R, W + 0.175 * R[:, :, 2]


def reachable_configs(n: int, lower: np.ndarray, upper: np.ndarray, seed: int) -> np.ndarray:
    rng = np.random.default_rng(seed)
    cos_tilt = math.cos(math.radians(5.0))
    out: list[np.ndarray] = []
    while sum(len(o) for o in out) < n:
        q = rng.uniform(lower, upper, size=(200_000, 7))
        R, p = _dh_fk_many(q)
        h = p[:, 2] - TABLE_Z
        r = np.hypot(p[:, 0], p[:, 1])
        keep = (-R[:, 2, 2] >= cos_tilt) & (h >= 0.01) & (h <= 0.30) & (r >= 0.25) & (r <= 0.90) & (p[:, 0] > 0)
        out.append(q[keep])
    return np.concatenate(out)[:n]


def topdown(x: float, y: float, z: float, yaw: float) -> np.ndarray:
    T = np.eye(4)
    c, s = math.cos(yaw), math.sin(yaw)
    T[:3, :3] = np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]]) @ DOWN
    T[:3, 3] = [x, y, z]
    return T


def random_rotation(rng: np.random.Generator) -> np.ndarray:
    Q, Rr = np.linalg.qr(rng.normal(size=(3, 3)))
    Q = Q * np.sign(np.diag(Rr))  # uniform (Haar)
    return Q if np.linalg.det(Q) > 0 else -Q


def near_axis_poses(n: int, seed: int) -> list[np.ndarray]:
    rng = np.random.default_rng(seed)
    out = []
    for _ in range(n):
        r, az = rng.uniform(0.0, 0.35), rng.uniform(-math.pi / 2, math.pi / 2)
        z = TABLE_Z + rng.uniform(0.01, 0.30)
        out.append(topdown(r * math.cos(az), r * math.sin(az), z, rng.uniform(-math.pi, math.pi)))
    return out


def any_orientation_poses(n: int, seed: int) -> list[np.ndarray]:
    rng = np.random.default_rng(seed)
    out = []
    for _ in range(n):
        r, az = rng.uniform(0.0, 0.90), rng.uniform(-math.pi / 2, math.pi / 2)
        T = np.eye(4)
        T[:3, :3] = random_rotation(rng)
        T[:3, 3] = [r * math.cos(az), r * math.sin(az), TABLE_Z + rng.uniform(0.01, 0.30)]
        out.append(T)
    return out


def beyond_reach_poses(n: int, seed: int) -> list[np.ndarray]:
    rng = np.random.default_rng(seed)
    out = []
    for i in range(n):
        r, az = rng.uniform(0.95, 1.6), rng.uniform(-math.pi, math.pi)
        x, y, z = r * math.cos(az), r * math.sin(az), TABLE_Z + rng.uniform(-0.3, 0.3)
        if i % 2 == 0:
            T = topdown(x, y, z, rng.uniform(-math.pi, math.pi))
        else:
            T = np.eye(4)
            T[:3, :3] = random_rotation(rng)
            T[:3, 3] = [x, y, z]
        out.append(T)
    return out


# -- solvers ---------------------------------------------------------------------------------


def old_module() -> Any | None:
    """clearcli/robot/kinematics.py as committed at OLD_REV (None if git cannot say)."""
    try:
        src = subprocess.run(
            ["git", "show", f"{OLD_REV}:clearcli/robot/kinematics.py"],
            cwd=REPO,
            capture_output=True,
            text=True,
            check=True,
        ).stdout
    except (OSError, subprocess.CalledProcessError):
        return None
    path = Path(tempfile.mkdtemp()) / "kinematics_head.py"
    path.write_text(src)
    spec = importlib.util.spec_from_file_location("kinematics_head", path)
    assert spec is not None and spec.loader is not None
    mod = importlib.util.module_from_spec(spec)
    sys.modules["kinematics_head"] = mod  # dataclasses look their module up
    spec.loader.exec_module(mod)
    mod.URDF_PATH = kin_mod.URDF_PATH  # the URDF beside the real module
    return mod


class Counted:
    """A WamKinematics (default settings) whose damped least squares runs are counted
    (the old code keeps no such statistic) and whose cache is emptied before every call."""

    def __init__(self, mod: Any) -> None:
        self.kin = mod.WamKinematics()
        self.starts = 0
        inner = self.kin._solve_from

        def counted(*args: Any, **kwargs: Any) -> Any:
            self.starts += 1
            return inner(*args, **kwargs)

        self.kin._solve_from = counted

    def sweeps(self) -> int:
        return int(getattr(self.kin.stats, "sweeps", 0))

    def ik(self, T: np.ndarray, warm: np.ndarray | None = None) -> tuple[np.ndarray | None, float]:
        self.kin._cache.clear()
        t0 = time.perf_counter()
        q = self.kin.ik(T, warm)
        return q, time.perf_counter() - t0


def verified(kin: Any, q: np.ndarray | None, T: np.ndarray) -> bool:
    """q within the joint limits and FK(q) within the tolerances of T."""
    if q is None or np.any(q < kin.lower) or np.any(q > kin.upper):
        return False
    got = kin.fk(q)
    R_err = got[:3, :3].T @ T[:3, :3]
    angle = math.acos(float(np.clip((np.trace(R_err) - 1.0) / 2.0, -1.0, 1.0)))
    return float(np.linalg.norm(got[:3, 3] - T[:3, 3])) < kin.tolerance_m and angle < kin.tolerance_rad


def thorough_solution(kin: Any, T: np.ndarray, n_starts: int = 48, iterations: int = 200) -> bool:
    """Damped least squares (the old solver's iteration) from many random starts."""
    rng = np.random.default_rng(99)
    target = kin.target(T)
    saved = kin.max_iterations
    kin.max_iterations = iterations
    try:
        for _ in range(n_starts):
            q = kin._solve_from(target, rng.uniform(kin.lower, kin.upper))
            if q is not None and verified(kin, q, T):
                return True
    finally:
        kin.max_iterations = saved
    return False


# -- runs ------------------------------------------------------------------------------------


def run(
    solvers: list[tuple[str, Counted]],
    poses: list[np.ndarray],
    warms: dict[str, list[np.ndarray | None]] | None = None,
) -> dict[str, list[Record]]:
    """Every solver on every pose, taking turns by blocks of BLOCK poses, so that a slow
    spell of the machine hits both alike (and each block starts with one call to warm the
    CPU caches after the other solver, not counted: pose by pose turns would time cold
    caches, which doubles a 20 us rejection)."""
    out: dict[str, list[Record]] = {who: [] for who, _ in solvers}
    for start in range(0, len(poses), BLOCK):
        for who, solver in solvers:
            solver.ik(poses[start], None if warms is None else warms[who][start])
            for i in range(start, min(start + BLOCK, len(poses))):
                T = poses[i]
                s0, w0 = solver.starts, solver.sweeps()
                q, dt = solver.ik(T, None if warms is None else warms[who][i])
                wrong = q is not None and not verified(solver.kin, q, T)
                out[who].append((q, dt, solver.starts - s0, solver.sweeps() - w0, wrong))
    return out


def summary(records: list[Record]) -> dict[str, float]:
    n = len(records)
    if n == 0:
        nan = math.nan
        return {"n": 0, "median_ms": nan, "p95_ms": nan, "success": nan, "starts": nan, "sweeps": nan, "bad": 0}
    times = sorted(r[1] for r in records)
    return {
        "n": n,
        "median_ms": 1000 * statistics.median(times),
        "p95_ms": 1000 * times[min(n - 1, int(0.95 * n))],
        "success": sum(r[0] is not None for r in records) / n,
        "starts": sum(r[2] for r in records) / n,
        "sweeps": sum(r[3] for r in records) / n,
        "bad": sum(r[4] for r in records),
    }


def no_solution_members(
    label: str, drawn: list[np.ndarray], solvers: list[tuple[str, Counted]]
) -> tuple[list[int], dict[str, list[Record]]]:
    """Run every solver on every drawn pose (these runs are the timings), then keep the
    poses nobody solves, the thorough search included."""
    t0 = time.perf_counter()
    recs = run(solvers, drawn)
    kin = solvers[0][1].kin
    members, misses_new, misses_old, solvable = [], 0, 0, 0
    has_old = "old" in recs
    for i, T in enumerate(drawn):
        a = recs["new"][i][0] if recs["new"][i][0] is not None else recs["swp"][i][0]
        b = recs["old"][i][0] if has_old else None
        if a is not None:
            solvable += 1
            misses_old += has_old and b is None
        elif b is not None or thorough_solution(kin, T):
            misses_new += 1
            misses_old += has_old and b is None
        else:
            members.append(i)
    print(
        f"({label}: drew {len(drawn)} in reach; {len(members)} without a solution, {solvable} solved by new/swp, "
        f"{misses_new} solved only by old or the thorough search (misses of the new)"
        + (f", {misses_old} solvable ones missed by old" if has_old else "")
        + f"; {time.perf_counter() - t0:.0f} s)"
    )
    return members, recs


def row(group: str, who: str, r: dict[str, float]) -> None:
    bad = f"  {int(r['bad'])} WRONG" if r["bad"] else ""
    print(
        f"{group:<32} {who:<4} {int(r['n']):>5} {r['median_ms']:>9.3f} {r['p95_ms']:>9.3f} "
        f"{100 * r['success']:>8.2f}% {r['starts']:>7.2f} {r['sweeps']:>7.2f}{bad}"
    )


def timed(f: Callable[[], Any], repeat: int) -> float:
    t0 = time.perf_counter()
    for _ in range(repeat):
        f()
    return (time.perf_counter() - t0) / repeat


def profile_bench(name: str, quick: bool) -> None:
    """The three groups of the module doc for one profile (--robot)."""
    from clearcli.robot.profiles import kinematics_from_settings
    from clearcli.robot.profiles import profile as get_profile
    from clearcli.settings import load_settings

    kin = kinematics_from_settings(load_settings(sets=[f"robot.name={name}"]).robot)
    prof = get_profile(name)
    table_z = -prof.base_above_footprint_m  # the table's plane in the base frame
    n1, n2, n3 = (200, 40, 100) if quick else (1000, 120, 300)
    rng = np.random.default_rng(1)
    reach: list[np.ndarray] = []
    while len(reach) < n1:
        T = kin.fk(rng.uniform(kin.lower, kin.upper))
        r = math.hypot(T[0, 3], T[1, 3])
        if T[2, 2] < -math.cos(math.radians(5)) and 0.01 <= T[2, 3] - table_z <= 0.30 and 0.25 <= r <= 0.80:
            reach.append(T)
    thorough = kinematics_from_settings(load_settings(sets=[f"robot.name={name}"]).robot)
    # "in reach": for a URDF arm, the flange within its links' summed lengths of the
    # shoulder (what its old bound let through; the measured bounds now refuse some of
    # these at once, which is what the group measures); the WAM: its own test
    links_m = getattr(kin, "links_stretch_m", None)

    def in_reach(T: np.ndarray) -> bool:
        if links_m is None:
            return bool(kin.reachable(T))
        M = np.asarray(kin.M_flange_tcp.homogeneous)
        flange = T[:3, 3] - T[:3, :3] @ (M[:3, :3].T @ M[:3, 3])
        return float(np.linalg.norm(flange - kin.shoulder_bound)) <= links_m + 0.005

    no_sol: list[np.ndarray] = []
    rng2 = np.random.default_rng(2)
    tries = 0
    while len(no_sol) < n2 and tries < 50 * n2:
        tries += 1
        az, r = rng2.uniform(-math.pi, math.pi), rng2.uniform(0.0, 0.9)
        T = np.eye(4)
        T[:3, :3] = random_rotation(rng2)
        T[:3, 3] = [r * math.cos(az), r * math.sin(az), table_z + rng2.uniform(0.01, 0.30)]
        if not in_reach(T) or thorough_solution(thorough, T):
            continue
        no_sol.append(T)
    far: list[np.ndarray] = []
    rng3 = np.random.default_rng(3)
    shoulder = np.asarray(getattr(kin, "shoulder_bound", np.zeros(3)), dtype=float)
    while len(far) < n3:
        d = rng3.normal(size=3)
        d /= np.linalg.norm(d)
        T = np.eye(4)
        T[:3, :3] = random_rotation(rng3)
        T[:3, 3] = shoulder + rng3.uniform(1.2, 1.6) * d
        far.append(T)

    def timed_group(poses: list[np.ndarray]) -> tuple[list[float], int, int]:
        times, ok, wrong = [], 0, 0
        for T in poses:
            kin._cache.clear()
            t = time.perf_counter()
            q = kin.ik(T)
            times.append(time.perf_counter() - t)
            if q is not None:
                ok += 1
                wrong += not verified(kin, q, T)
        return times, ok, wrong

    print(f"robot {name}: {prof.summary}")
    print(f"{'group':<34} {'poses':>5} {'median ms':>9} {'p95 ms':>9} {'solved':>8}")
    for label, poses in (
        ("(1) reachable tool-down", reach),
        ("(2) in reach, no solution", no_sol),
        ("(3) beyond reach: ik()", far),
    ):
        times, ok, wrong = timed_group(poses)
        ms = np.array(times) * 1000
        print(
            f"{label:<34} {len(poses):>5} {np.median(ms):>9.3f} {np.percentile(ms, 95):>9.3f} {100 * ok / max(len(poses), 1):>7.1f}%"
            + (f"  WRONG {wrong}" if wrong else "")
        )
    if links_m is not None:
        at_once = sum(not kin.reachable(T) for T in no_sol)
        print(f"    of group (2), {at_once} refused at once by the measured reach bounds")
    per_call = timed(lambda: [kin.reachable(T) for T in far], 5) / len(far)
    print(f"{'(3) beyond reach: reachable()':<34} {len(far):>5} {1000 * per_call:>9.4f} (mean)")


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--quick", action="store_true")
    ap.add_argument("--no-old", action="store_true", help="skip the replaced solver (OLD_REV)")
    ap.add_argument("--robot", help="a profile (clear robots), or all: the profile groups of the module doc")
    args = ap.parse_args()
    if args.robot:
        from clearcli.robot.profiles import PROFILES

        for name in list(PROFILES) if args.robot == "all" else [args.robot]:
            profile_bench(name, args.quick)
            print()
        return
    n1, n2, n2b, n3 = (400, 60, 40, 200) if args.quick else (2000, 300, 200, 500)

    new = Counted(kin_mod)
    sweep = Counted(kin_mod)
    sweep.kin.track_iterations = 0  # the swivel sweep alone, no damped least squares first
    old_mod = None if args.no_old else old_module()
    old = Counted(old_mod) if old_mod is not None else None
    solvers = [("new", new), ("swp", sweep)] + ([("old", old)] if old is not None else [])

    t0 = time.perf_counter()
    reach = [new.kin.fk(q) for q in reachable_configs(n1, new.kin.lower, new.kin.upper, seed=1)]
    higher = []
    for T in reach:
        T2 = T.copy()
        T2[2, 3] += 0.05
        higher.append(T2)
    print(f"(1: drew {len(reach)} reachable poses in {time.perf_counter() - t0:.1f} s)")
    near = [T for T in near_axis_poses(n2, seed=2) if new.kin.reachable(T)]
    near_members, near_recs = no_solution_members("2", near, solvers)
    anyo = [T for T in any_orientation_poses(n2b, seed=4) if new.kin.reachable(T)]
    any_members, any_recs = no_solution_members("2b", anyo, solvers)
    far = beyond_reach_poses(n3, seed=3)
    assert not any(new.kin.reachable(T) for T in far)

    print()
    print(
        f"{'group':<32} {'who':<4} {'poses':>5} {'median ms':>9} {'p95 ms':>9} {'success':>9} "
        f"{'starts':>7} {'sweeps':>7}"
    )
    results: dict[tuple[str, str], dict[str, float]] = {}
    rec1 = run(solvers, reach)
    rec1w = run(solvers, higher, {who: [r[0] for r in recs] for who, recs in rec1.items()})
    rec3 = run(solvers, far)
    for who, solver in solvers:
        results["1", who] = summary(rec1[who])
        row("(1) reachable", who, results["1", who])
        row("(1w) 5 cm up, warm-started", who, summary(rec1w[who]))
        results["2", who] = summary([near_recs[who][i] for i in near_members])
        row("(2) no solution, top-down", who, results["2", who])
        results["2b", who] = summary([any_recs[who][i] for i in any_members])
        row("(2b) no solution, any orient.", who, results["2b", who])
        results["3", who] = summary(rec3[who])
        row("(3) beyond reach: ik()", who, results["3", who])
        per_call = timed(lambda: [solver.kin.reachable(T) for T in far], 5) / len(far)  # noqa: B023 (timed within the iteration)
        print(f"{'(3) beyond reach: reachable()':<32} {who:<4} {len(far):>5} {1000 * per_call:>9.4f} (mean)")
    if old is not None:
        print()
        ratios = [results[g, "old"]["median_ms"] / results[g, "new"]["median_ms"] for g in ("1", "2", "2b", "3")]
        print(
            "median speed-up, old/new: " + ", ".join(f"({g}) {r:.1f}x" for g, r in zip(("1", "2", "2b", "3"), ratios))
        )


if __name__ == "__main__":
    main()
