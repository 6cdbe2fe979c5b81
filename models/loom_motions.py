"""Old path of mechopt.models.cyclogram_motions, kept for one release: the same module."""
import sys

from mechopt.models import cyclogram_motions

sys.modules[__name__] = cyclogram_motions
