"""Old path of mechopt.models.cyclogram, kept for one release: the same module."""
import sys

from mechopt.models import cyclogram

sys.modules[__name__] = cyclogram
