"""Pure geometry (numpy only): Plücker lines, the unit sphere, SE(3), ruled surfaces."""
