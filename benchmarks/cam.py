"""The cam wing's accuracy against time: `size_cam`'s largest pressure angle on a translating
offset roller (cycloidal rise-dwell-return-dwell) against the hand formula on 10^6 angles, and
its time as a ratio to the coarsest sampling's, measured in the same process. The extremes are
polished between samples, so even 360 samples meet the reference (itself on a 10^6 grid)."""
import math
import time

import numpy as np

SAMPLES = (360, 3600, 36_000)


class _Cycloid:
    """A 20 mm cycloidal rise over 120 deg, dwell 60, return over 120, dwell (closed form)."""

    def at(self, theta):
        th = np.mod(np.atleast_1d(theta), 2 * math.pi)
        b = 2 * math.pi / 3
        x = np.clip(np.where(th < math.pi, th, th - math.pi) / b, 0, 1)
        s = 20 * (x - np.sin(2 * math.pi * x) / (2 * math.pi))
        v = 20 * (1 - np.cos(2 * math.pi * x)) / b * (x < 1)
        a = 20 * 2 * math.pi * np.sin(2 * math.pi * x) / b**2
        back = th >= math.pi
        return np.where(back, 20 - s, s), np.where(back, -v, v), np.where(back, -a, a), np.zeros_like(th)


def cli(repeats, out_dir, progress=None, quick=False) -> str:
    from mechopt.models.cam_followers import CamFollower
    from mechopt.solvers.cam import size_cam

    task = CamFollower(base_radius_mm=40.0, roller_radius_mm=10.0, offset_mm=8.0, motion=_Cycloid())
    theta = np.linspace(0, 2 * math.pi, 1_000_000, endpoint=False)
    s, ds, _, _ = task.motion.at(theta)
    exact = float(np.degrees(np.abs(np.arctan((ds - 8.0) / (math.sqrt(50.0**2 - 64.0) + s)))).max())
    size_cam(task, samples=SAMPLES[0])            # imports (scipy) outside the timing
    rows, base = [], None
    for n in SAMPLES[:2] if quick else SAMPLES:
        start = time.process_time()
        for _ in range(max(1, repeats)):
            got = size_cam(task, samples=n).values["max_pressure_angle_deg"]
        cpu = (time.process_time() - start) / max(1, repeats)
        base = base or cpu
        rows.append(f"{n:>8} samples: error {abs(got - exact):.2e} deg, CPU x{cpu / base:.2f} of {SAMPLES[0]} samples")
    return "cam: size_cam's largest pressure angle against the hand formula\n" + "\n".join(rows)
