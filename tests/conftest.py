"""Shared test settings: property tests draw the same examples on every run, so CI cannot flake,
and nothing the suite runs leaves files in the checkout (hypothesis keeps its folder in a temp dir)."""
import os
import tempfile

os.environ.setdefault("HYPOTHESIS_STORAGE_DIRECTORY", os.path.join(tempfile.gettempdir(), "mechopt-hypothesis"))

from hypothesis import settings  # noqa: E402  (after the storage folder is set)

settings.register_profile("mechopt", derandomize=True, database=None, deadline=None)
settings.load_profile("mechopt")
