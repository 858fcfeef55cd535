"""credal-fusion core: belief functions, association, tracking and fusion.

Pure Python + numpy/scipy/filterpy. Nothing here imports fastapi, pydantic or
``app``: the package is usable as a library on its own.
"""

__version__ = "0.1.0"
