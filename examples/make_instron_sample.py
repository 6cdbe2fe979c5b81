"""Writes examples/instron-sample.csv: a GENERATED load-travel record, not a measurement.

The load is eq. (1) of paper 001 with the coefficients of the press/kd2322 scene (read from the
scene, not typed here), over the blank thickness, plus 1 % seeded noise, as a testing machine would
export it (semicolon-separated, header with units). `mechopt fit-force examples/instron-sample.csv`
should give back the scene's coefficients within the noise.
"""
from pathlib import Path

import numpy as np

import mechopt
from mechopt.models.press_laws import FORCE_KEYS, cutting_force_N

scene = mechopt.load("press/kd2322")
coefficients = [scene.params()[k] for k in FORCE_KEYS]
travel_mm = np.linspace(0.0, scene.params()["blank_thickness_mm"], 61)
load_N = cutting_force_N(travel_mm, *coefficients)
load_N = load_N * (1 + 0.01 * np.random.default_rng(1).standard_normal(travel_mm.size))
lines = ["Travel_mm;Load_N"] + [f"{x:.4f};{f:.2f}" for x, f in zip(travel_mm, load_N)]
Path(__file__).with_name("instron-sample.csv").write_text("\n".join(lines) + "\n", encoding="utf-8")
