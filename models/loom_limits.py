"""The STB loom's own limits on an operation's phase angle (paper 004: Podgorny et al. 2018), the
laws a cyclogram's operation may name (`stress`, `amplitude`, the `lever` table).


Contact stress (our reading; the paper gives no law): a cam pair under inertial load carries
F = m h omega^2 C / t^2 (lift h over phase angle t, C the law's acceleration coefficient), and
the Hertz line-contact stress grows as sqrt(F), so sigma_max(t) = sigma_ref t_ref / t: one
reference point (t_ref, sigma_ref) per cam pair fixes the curve. sigma_max <= [sigma_H] is then
exactly t >= sigma_ref t_ref / [sigma_H] ("turned into a bound on the phase angle"); its tangent
at t_ref, `stress_bound_deg(..., form="linear")`, is the linearisation a linear design asks for.
At another speed n the inertial load scales as n^2, so sigma_max(t, n) = sigma_ref (t_ref / t)
(n / n_ref), n_ref the speed of the references: a function of n / t alone, as the rebound is:
the cam's rise in its own time depends on t / n only (lambda = omega t / Omega), so v0, the
pulse and the first rebound are a function h(n / t), not proportional to it, and h is wavy (the
lever rings during the rise): a(t) <= limit is then not one bound from one tangent.
"""
import dataclasses

from mechopt.kit.errors import MechoptError, ModelError
from mechopt.models.cyclogram_tables import NOTE_KEYS, check_entry, check_table, finite_number
from mechopt.models.stop_impact import LeverStop

STRESS_FORMS = ("exact", "linear")
AMPLITUDE_LAWS = ("linear",)


def stress_MPa(sigma_ref_MPa, t_ref_deg, t_deg):
    """Maximum contact stress of a cam pair moved over phase angle t [MPa]: sigma_ref t_ref / t
    (Hertz sigma ~ sqrt(inertial load), load ~ 1/t^2; see the module docstring)."""
    return sigma_ref_MPa * t_ref_deg / t_deg


def stress_bound_deg(sigma_ref_MPa, t_ref_deg, sigma_H_MPa, form="exact"):
    """Smallest phase angle with sigma_max(t) <= [sigma_H] [deg].

    ``exact``: t >= sigma_ref t_ref / [sigma_H]. ``linear``: the tangent of sigma_max at t_ref,
    sigma_ref (2 - t / t_ref) <= [sigma_H], i.e. t >= t_ref (2 - [sigma_H] / sigma_ref). The
    curve is convex, so the tangent lies under it: the linear bound is never above the exact one.
    """
    if form == "exact":
        return sigma_ref_MPa * t_ref_deg / sigma_H_MPa
    if form == "linear":
        return t_ref_deg * (2.0 - sigma_H_MPa / sigma_ref_MPa)
    raise ModelError(f"stress_form={form!r}: allowed {', '.join(STRESS_FORMS)}", key="stress_form")


def amplitude_mm(slope_mm_per_deg, intercept_mm, t_deg):
    """Vibration amplitude of the working member after its stop, linearised in t [mm]:
    a(3,7) = slope t(3,7) + intercept (paper 004, the law before Conclusions)."""
    return slope_mm_per_deg * t_deg + intercept_mm


def amplitude_bound_deg(slope_mm_per_deg, intercept_mm, limit_mm):
    """Smallest phase angle with a(t) <= limit [deg] (slope < 0): (intercept - limit) / -slope."""
    return (limit_mm - intercept_mm) / slope_mm_per_deg


def lever_stop(table) -> LeverStop:
    """The lift lever of the stop-impact model (models/stop_impact.py) from a scene's
    [structure.lever] table: LeverStop's parameters, each a number or {value, mark, why / where /
    on}, its `effects` and the cam's motion `law` (a name, effect cam_drive). The one place the
    cyclogram couples to the stop model."""
    check_table(table, "lever", dict)
    args = {}
    for key, entry in table.items():
        if key in ("effects", "law", "closure"):      # names, not numbers
            args[key] = entry
            continue
        if isinstance(entry, dict):
            check_entry(entry, f"lever.{key}", {"value", "on"} | NOTE_KEYS, required=("value",))
            entry = entry["value"]
        args[key] = finite_number(entry, f"lever.{key}")
    known = {f.name for f in dataclasses.fields(LeverStop)}
    unknown = sorted(set(args) - known)
    if unknown:
        raise ModelError(f"lever: unknown {', '.join(unknown)}; allowed: {', '.join(sorted(known))}", key="lever")
    try:
        return LeverStop(**args)
    except MechoptError as exc:
        raise ModelError(f"lever.{exc}", key=f"lever.{exc.key}" if exc.key else "lever") from None
    except TypeError as exc:            # a required parameter missing
        raise ModelError(f"lever: {exc}", key="lever") from None

