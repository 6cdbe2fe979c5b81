"""The groove's rise with its backlash: the exact phases (`follow_groove`) against the DOP853
hybrid (`follow_groove_ivp`, the path before), in one process, CPU seconds per rise
(time.process_time), medians over repeats, interleaved, on stop-impact/cam-dynamics-groove's
lever at speeds that cross over (each with one flight or more) and one that does not; beside
them the largest relative difference in v0 (the DOP853 hybrid's own error at rtol 1e-11 is of
that order: tests/stop_impact/test_groove.py). And the chain's v0 where the exact rise has no
flight (the driving wall's rise): the exact phases (`follow_groove_exact`, what the chain now
takes there) against the CVODES rise (`follow_cam`, what it ran there before), with their largest
relative difference in v0. `mechopt bench groove`."""
import statistics
import time

from mechopt import registry

__all__ = ["cli", "in_process", "plain_rises"]

SCENE, SPEEDS_RPM = "stop-impact/cam-dynamics-groove", (400.0, 520.0, 600.0, 700.0)
PLAIN_POINTS = [(n, t) for n in (300.0, 520.0) for t in (None, 50.0)]     # (rpm, deg; None: the lever's t)


def in_process(repeats=3, progress=None):
    """{"exact": s per rise, "dop853": s per rise, "v0_rel": largest |v0 / v0_ivp - 1|}."""
    from mechopt.solvers.stop_impact.groove import follow_groove, follow_groove_ivp
    task = registry.find(SCENE).build()[0]
    follow_groove(task, SPEEDS_RPM[0])                  # first-use costs (the sample grid's integrals)
    times, worst = {"exact": [], "dop853": []}, 0.0
    for i in range(repeats):
        for name, run in (("exact", follow_groove), ("dop853", follow_groove_ivp)):
            start = time.process_time()
            rises = [run(task, n) for n in SPEEDS_RPM]
            times[name].append((time.process_time() - start) / len(SPEEDS_RPM))
            if name == "exact":
                exact = rises
        worst = max([worst] + [abs(a.approach_velocity_m_s / b.approach_velocity_m_s - 1) for a, b in zip(exact, rises)])
        if progress:
            progress(f"repeat {i + 1}: exact {times['exact'][-1] * 1e3:.2f} ms, DOP853 {times['dop853'][-1] * 1e3:.1f} ms")
    return {k: statistics.median(v) for k, v in times.items()} | {"v0_rel": worst}


def plain_rises(repeats=3):
    """{"exact": s per rise, "cvodes": s per rise, "v0_rel": largest |v0 / v0_CVODES - 1|} at the
    PLAIN_POINTS where the exact rise has no flight before its contact."""
    from mechopt.solvers.stop_impact.cam_follower import follow_cam
    from mechopt.solvers.stop_impact.groove import follow_groove_exact
    from mechopt.solvers.stop_impact.law import CHAIN_RELTOL
    task = registry.find(SCENE).build()[0]
    points = [(n, task.t_deg if t is None else t) for n, t in PLAIN_POINTS]
    points = [p for p in points if not follow_groove_exact(task, *p).flights]
    times, worst = {"exact": [], "cvodes": []}, 0.0
    for _ in range(repeats):
        for name, run in (("exact", lambda p: follow_groove_exact(task, *p)),
                          ("cvodes", lambda p: follow_cam(task, *p, reltol=CHAIN_RELTOL))):
            start = time.process_time()
            rises = [run(p) for p in points]
            times[name].append((time.process_time() - start) / len(points))
            if name == "exact":
                exact = rises
        worst = max([worst] + [abs(a.approach_velocity_m_s / b.approach_velocity_m_s - 1)
                               for a, b in zip(exact, rises)])
    return {k: statistics.median(v) for k, v in times.items()} | {"v0_rel": worst, "points": len(points)}


def cli(repeats, out_dir, progress=None, quick=False) -> str:
    """The table alone (no figure)."""
    got = in_process(repeats=1 if quick else min(repeats, 5), progress=progress)
    return "\n".join([f"groove rise (per rise, CPU, median; {SCENE} at {', '.join(f'{n:g}' for n in SPEEDS_RPM)} rpm)",
                      f"  exact phases   {got['exact'] * 1e3:8.2f} ms",
                      f"  DOP853 hybrid  {got['dop853'] * 1e3:8.2f} ms",
                      f"  ratio          {got['dop853'] / got['exact']:8.1f} x",
                      f"  largest |v0 / v0_DOP853 - 1|: {got['v0_rel']:.1e}"] + _plain_lines(repeats, quick))


def _plain_lines(repeats, quick):
    got = plain_rises(repeats=1 if quick else min(repeats, 5))
    return [f"driving wall's rise, no flight (per rise, CPU, median; {got['points']} points)",
            f"  exact phases   {got['exact'] * 1e3:8.2f} ms",
            f"  CVODES rise    {got['cvodes'] * 1e3:8.2f} ms",
            f"  ratio          {got['cvodes'] / got['exact']:8.1f} x",
            f"  largest |v0 / v0_CVODES - 1|: {got['v0_rel']:.1e}"]
