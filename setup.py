"""The package list is discovered, not written by hand: a folder added under one of the mapped roots
cannot silently drop out of the wheel (tests/spine/test_wheel.py builds the wheel and imports every module)."""
from setuptools import find_packages, setup

# import name -> folder; pyproject.toml holds everything else
ROOTS = {"mechopt": "src/mechopt", "mechopt.models": "models", "mechopt.solvers": "solvers",
         "mechopt.cases": "cases", "mechopt.benchmarks": "benchmarks"}

packages, package_dir = [], {}
for name, folder in ROOTS.items():
    package_dir[name] = folder
    packages += [name] + [f"{name}.{sub}" for sub in find_packages(folder)]

setup(packages=packages, package_dir=package_dir)
