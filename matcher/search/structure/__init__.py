"""The structure search: rank every pose the prior allows (the whole floor
when lost) by the building's structure, then verify the best few with
stage 2.

    observed.py  the frame's lines in the robot's frame: level-line
                 directions, vertical-line bearings, floor and ceiling samples
    yaw.py       yaw hypotheses: level lines against the map's wall directions
    profiles.py  what the search uses from the map, per floor point and
                 bearing (junction distances, vertical edges in sight),
                 derived once per map
    score.py     every (place, yaw) scored at once
    peaks.py     the best peaks (the second is the best pose elsewhere),
                 refined below the grid's step
    ranking.py   the above in order, for one frame
    localize.py  the peaks verified by stage 2, judged by the one verdict

Every tolerance is derived from the camera's noise (``line_px``,
``line_deg``, through each line's plane and bearing noise), the map's error
(``model_m``) and the grids the matcher already has (``yaw_step_deg``,
``Stage1Constants.region_step_m``); the one constant of its own is
``SharedConstants.yaw_peak_share``.
"""
