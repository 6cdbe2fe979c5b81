"""Numerics: turn a model's question into a formal problem, solve it, return a `Result`."""
