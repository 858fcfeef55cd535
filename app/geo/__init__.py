"""Sensors in the world: WGS84 geodesy and the session frame, polar detections, GeoJSON output."""
