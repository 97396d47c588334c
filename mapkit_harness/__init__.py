"""The test and benchmark harness: what the tests in ``tests/`` and the
scripts in ``tools/`` share, installed with the project (``pip install -e .``)
so that both import it by name.

Ground truth and simulated input, one concept per module:

- :mod:`.plans`: synthetic plans with known geometry (buildings in code,
  DXF drawings, the example plan ``maps/flat.dxf``, meshes);
- :mod:`.simulate`: frames of the paper's protocol from a map and a camera
  (``make_frame``, ``paper_camera``, ``visible_lines``, ``pose_error``), and
  a rig's frames (``make_rig_frame``);
- :mod:`.rigs`: the camera rigs of the tests and benchmarks (``ring_rig``);
- :mod:`.runs`: a robot driving through a map (route, odometry, frames);
- :mod:`.render`: grey images of a map seen from a pose;
- :mod:`.panorama`: perspective views cut from an equirectangular panorama;
- :mod:`.visibility_oracle`: brute-force visibility, the reference;
- :mod:`.crafted_maps`: ``.lmap`` files with valid checksums and hostile contents;
- :mod:`.fuzz`: the fuzz families (damaged and hostile inputs for every entry
  point), the bounded run of a case, the classifier and the campaign;
- :mod:`.baseline`: the classic interpretation tree the paper sets out to beat;
- :mod:`.scoring`: whether a matcher's answer is right, for the benchmarks;
- :mod:`.browser`: headless chromium over the DevTools protocol, and a
  websocket client of the inspector;
- :mod:`.tables`: the benchmarks' markdown tables and ``--report`` files.

The shipped packages (``linemap``, ``mapkit``, ``matcher``) never import it
(``tests/test_layout.py``).
"""
