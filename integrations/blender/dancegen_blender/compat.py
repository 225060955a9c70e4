"""Shims for the glTF importer of Blender 3.4 (Debian's) on numpy 1.24 and later, which removed
`numpy.bool` that the importer still uses. Harmless where it is not needed."""

import warnings


def patch_numpy_bool():
    try:
        import numpy
    except ImportError:
        return
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        if not hasattr(numpy, "bool"):
            numpy.bool = bool
