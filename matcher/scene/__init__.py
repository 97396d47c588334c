"""What the map says about where the camera can stand and what it can see,
derived once per map (:class:`~matcher.map_index.MapIndex`):

- :mod:`~matcher.scene.freespace`: distance to the floor the robot can reach;
- :mod:`~matcher.scene.occlusion`: the walls as occluders, sight lines and
  the sight table of vertical edges, wall-face sides;
- :mod:`~matcher.scene.collinear`: segments on one 3D line.
"""
