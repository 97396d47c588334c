"""Following a moving robot with its odometry (:class:`Tracker`).

- :mod:`~matcher.tracking.odometry`: pose increments and the estimate's spread;
- :mod:`~matcher.tracking.tracker`: the tracker and its three states;
- :mod:`~matcher.tracking.frames`: runs as JSON Lines;
- :mod:`~matcher.tracking.rosbag`: runs as ROS 1/ROS 2 bags and MCAP files;
- :mod:`~matcher.tracking.rig_sync`: a rig's images in a bag grouped into instants;
- :mod:`~matcher.tracking.trajectory`: the TUM trajectory format;
- :mod:`~matcher.tracking.route_plot`: a picture of a run.
"""

from matcher.tracking.tracker import TrackedFrame, Tracker

__all__ = ["TrackedFrame", "Tracker"]
