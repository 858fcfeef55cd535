"""credal-fusion core: belief functions, association, tracking and fusion.

Pure Python + numpy/scipy/lapx/shapely (tests/test_dependencies.py checks it).
Nothing here imports fastapi, pydantic, ``evaluation`` or
``app``: the package is usable as a library on its own.
"""

__version__ = "0.1.0"
