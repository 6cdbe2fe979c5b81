"""Units read from names: every value and parameter carries its unit as a suffix (`H_mm`,
`peak_belt_torque_Nm`, `speed_rad_s`); this turns the suffix into a printable unit."""

# longest suffix first: "_N_per_mm" before "_mm", "_rad_s" before "_s"
SUFFIXES = (
    ("_mm_per_deg", "mm/deg"), ("_Nms_rad", "N m s/rad"), ("_Nm_rad", "N m/rad"), ("_N_per_mm", "N/mm"), ("_N_per_m", "N/m"), ("_kgm2", "kg m²"), ("_rad_s2", "rad/s²"),
    ("_rad_s", "rad/s"), ("_m_s2", "m/s²"), ("_m_s", "m/s"), ("_N_mm4", "N/mm⁴"), ("_N_mm3", "N/mm³"),
    ("_N_mm2", "N/mm²"), ("_N_mm", "N/mm"), ("_N_m", "N m"), ("_Nm", "N m"), ("_Ns", "N s"), ("_MPa", "MPa"),
    ("_GPa", "GPa"), ("_Hz", "Hz"), ("_rpm", "rpm"), ("_deg", "deg"), ("_rad", "rad"), ("_mm", "mm"), ("_kg", "kg"),
    ("_J", "J"), ("_N", "N"), ("_s", "s"), ("_m", "m"), ("_W", "W"),
)


def unit_of(name: str) -> str:
    """The unit a name's suffix states ('' when it states none: a ratio, a count)."""
    return next((unit for suffix, unit in SUFFIXES if name.endswith(suffix)), "")


def label(name: str) -> str:
    """A name as an axis label: words and unit, `err_width_mm` -> "err width [mm]"."""
    unit = unit_of(name)
    suffix = next((sfx for sfx, u in SUFFIXES if name.endswith(sfx)), "")
    words = (name[: -len(suffix)] if suffix else name).replace("_", " ")
    return f"{words} [{unit}]" if unit else words
