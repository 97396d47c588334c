"""What the map says about where the camera can stand and what it can see,
derived once per map (:class:`~matcher.map_index.MapIndex`):

- :mod:`~matcher.map_geometry.freespace`: distance to the floor the robot can reach;
- :mod:`~matcher.map_geometry.occlusion`: the walls as occluders, sight lines and
  the sight table of vertical edges, wall-face sides;
- :mod:`~matcher.map_geometry.collinear`: segments on one 3D line.
"""
