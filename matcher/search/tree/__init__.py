"""Stage 1 of the method: hypothesis generation (method.md sections 3 to 7).

No pose is computed: each test says whether a correspondence, a couple or a
set can hold for some pose of the prior set. In pipeline order:

- :mod:`~matcher.search.tree.constraints`: the paper's unary, binary and vertical tests;
- :mod:`~matcher.search.tree.correspondences`: the pairs that pass them, with
  their pose strips, yaw masks and half-planes on the pose grid;
- :mod:`~matcher.search.tree.posegrid`: the strips as quadratics, their minima
  and feasible regions;
- :mod:`~matcher.search.tree.pairwise`: which correspondences can hold together;
- :mod:`~matcher.search.tree.tree` (with :mod:`~matcher.search.tree.tree_input` and
  :mod:`~matcher.search.tree.set_visibility`): the interpretation tree's maximal
  consistent sets, each in free space and seeing its segments;
- :mod:`~matcher.search.tree.generate`: the three steps for one prior;
- :mod:`~matcher.search.tree.resection`: a second source of hypotheses, poses
  resected from triples of vertical edges.
"""
