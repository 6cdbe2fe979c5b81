"""The cam law library (the knowledge lives in models/cam_laws.py)::

    from mechopt import laws
    laws.names()                                    # ('cycloidal', 'harmonic', 'modified_sine', ...)
    law = laws.law("cycloidal")
    S, dS, ddS, dddS = law.values(xi)               # a unit rise over 0 <= xi <= 1 (d/dxi)
    law.peaks                                       # {"Cv": 2.0, "Ca": 6.2832, "Cj": 39.478}
    laws.polynomial([(0, 0, 0), (0, 1, 0), (0, 2, 0), (1, 0, 1), (1, 1, 0), (1, 2, 0)])   # degree 5: 3-4-5
    laws.scca(0.25, 0.75)                           # the sine-constant-cosine family (modified sine)

An unknown name is a ModelError listing the names.
"""
from mechopt.models.cam_laws import Law, law, names, numeric_law, polynomial, scca

__all__ = ["Law", "law", "names", "numeric_law", "polynomial", "scca"]
