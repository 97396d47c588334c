"""The map inspector behind ``mapkit view``: a browser view of a ``.lmap`` map.

Modules, one concept each (``server``, ``scene_nodes``, ``pose_tool``,
``result_overlay``, ``panel`` and ``snapshot`` draw with viser; the rest is
numpy/shapely and testable alone):

- :mod:`~mapkit.view.geometry`: region polygons, their triangulation, ring
  edges, the wall extrusion: the arrays the scene is drawn from.
- :mod:`~mapkit.view.palette`: colours of segment kinds and regions.
- :mod:`~mapkit.view.synthetic_image`: the model as the camera would see it.
- :mod:`~mapkit.view.result`: reading a matcher result and image lines.
- :mod:`~mapkit.view.stats`: the numbers shown in the panel.
- :mod:`~mapkit.view.scene_nodes`: the static 3D layers (batched viser calls).
- :mod:`~mapkit.view.pose_tool`: uncertainty disk, retained regions,
  candidate segments (the matcher's field-of-view test,
  :func:`linemap.geometry.in_field_of_view`), frustum and synthetic image
  for a pose estimate.
- :mod:`~mapkit.view.result_overlay`: a matcher result over the map.
- :mod:`~mapkit.view.panel`: the GUI panel (legend, toggles, pose controls).
- :mod:`~mapkit.view.server`: :class:`~mapkit.view.server.Inspector`, which
  ties them together and reacts to clicks and pose changes.
- :mod:`~mapkit.view.snapshot`: a standalone HTML file of the scene.

The headless-chromium driver of the browser test and the README screenshot
and the synthetic flat they use are not here: they are the harness's
(:mod:`mapkit_harness.browser`, :func:`mapkit_harness.plans.grid_flat`).
"""
