"""Stage 2 of the method: verification (method.md section 8).

For every hypothesis of stage 1, in order, on their matches held as one
structure (:mod:`~matcher.stage2.matches`):

- :mod:`~matcher.stage2.refine`: the least-squares pose (Gauss-Newton, robust
  first) and the paper's score E;
- :mod:`~matcher.stage2.fit`: the one fit test of a line to its segment at a
  pose, the visibility test, the piece of a collinear group a line shows;
- :mod:`~matcher.stage2.slide`: a loosely fixed pose moved to where its
  lines lie inside their segments;
- :mod:`~matcher.stage2.extend`: unmatched lines that fit visible segments
  added back;
- :mod:`~matcher.stage2.covariance`: how well the matches fix the pose;
- :mod:`~matcher.stage2.rank`: all of the above in order, then the ranking
  and the reason when nothing holds;
- :mod:`~matcher.stage2.calibration_check`: the accepted pose's matches
  fitted again with a calibration parameter free, for the verdict (is the
  camera file wrong?).
"""
