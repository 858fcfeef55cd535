"""PROJ (pyproj) as the independent oracle of the service's geodesy."""

from __future__ import annotations

from pyproj import Transformer


def proj_enu(origin: tuple[float, float, float]) -> Transformer:
    """PROJ's geodetic (lat°, lon°, h) → topocentric ENU at ``origin`` (inverse: direction="INVERSE")."""
    lat0, lon0, h0 = origin
    return Transformer.from_pipeline(
        "+proj=pipeline +step +proj=axisswap +order=2,1 +step +proj=unitconvert "
        "+xy_in=deg +xy_out=rad +step +proj=cart +ellps=WGS84 "
        f"+step +proj=topocentric +ellps=WGS84 +lat_0={lat0} +lon_0={lon0} +h_0={h0}"
    )
