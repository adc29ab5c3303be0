"""BoundED: sharp edges and boundaries in 3D point clouds, from the point positions alone.

The functions and classes are the native module's (``bounded._bounded``);
``bounded.distributed`` labels the tiles of a survey on a Dask cluster.
"""

from ._bounded import *  # noqa: F401,F403
from ._bounded import __version__  # noqa: F401
