"""Accuracy-vs-time studies, run by `mechopt bench` (timings are measured here, never asserted in tests)."""
