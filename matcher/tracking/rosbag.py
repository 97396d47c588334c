"""Frames of a run from a ROS 1 bag, a ROS 2 bag or an MCAP file.

Read with ``rosbags`` (no ROS install needed; ``pip install 'mapkit[ros]'``).
Three topics are used, each found by its message type when not named:

- images: ``sensor_msgs/Image`` (mono8, bgr8, rgb8, bgra8, rgba8, mono16)
  or ``sensor_msgs/CompressedImage`` (JPEG, PNG);
- intrinsics: ``sensor_msgs/CameraInfo`` (its first message), unless a
  camera file is given;
- odometry: ``nav_msgs/Odometry``, interpolated at each image's header
  time stamp (an image farther than ``Tracking.odom_max_gap_s`` from any
  odometry message is a frame with an error).

A camera rig's bag has one image topic per camera (``image_topics``, in
the rig's order; the rig file gives the cameras, so no intrinsics topic is
read): its frames are the instants of :mod:`matcher.tracking.rig_sync`,
one image a camera, with the odometry at the instant's time. An instant
missing a camera's image is a frame with an error naming the camera's
topic: the rig's verdict weighs what every camera should see, and a
missing view would count as a camera seeing none of its map lines.
"""

from __future__ import annotations

import bisect
import math
from collections.abc import Iterator
from pathlib import Path

import numpy as np

from linemap.errors import InputError
from matcher.tolerances import TRACKING
from matcher.tracking.frames import FrameInput
from matcher.tracking.odometry import wrap_deg

IMAGE_TYPES = ("sensor_msgs/msg/Image", "sensor_msgs/msg/CompressedImage")
INFO_TYPE = "sensor_msgs/msg/CameraInfo"
ODOM_TYPE = "nav_msgs/msg/Odometry"


class BagError(InputError):
    """A bag that cannot be followed: unreadable, or without the topics asked for."""


def is_bag(path: str | Path) -> bool:
    """Does ``path`` name a bag rather than a JSON Lines file: a ROS 1 ``.bag``,
    an ``.mcap`` or ``.db3`` file, or a ROS 2 bag folder (with metadata.yaml)?"""
    p = Path(path)
    return p.suffix in (".bag", ".mcap", ".db3") or (p.is_dir() and (p / "metadata.yaml").is_file())


class BagFrames:
    """The frames of a bag: ``camera_info`` (``k`` = fx, fy, cx, cy, ``size``,
    ``distortion``; None without an intrinsics topic), ``len()`` the
    number of images, iteration the :class:`FrameInput` of each, with its
    lines detected by ``detect(image array) -> lines``.

    A rig's bag (``image_topics``, one topic a camera in the rig's order,
    ``''`` where the rig does not name it: an error listing the bag's image
    topics): ``len()`` the images of its busiest camera, the frames its
    instants, ``detect(image array, k) -> lines`` for camera ``k``."""

    def __init__(self, path: str | Path, image_topic: str | None = None, info_topic: str | None = None,
                 odom_topic: str | None = None, max_gap_s: float = TRACKING.odom_max_gap_s,
                 image_topics: list[str] | None = None) -> None:
        try:
            from rosbags.highlevel import AnyReader
            from rosbags.typesys import Stores, get_typestore
        except ImportError:
            raise BagError("reading bags needs the rosbags package: pip install 'mapkit[ros]' (or rosbags)") from None
        self.path, self.max_gap_s = Path(path), max_gap_s
        try:
            self._reader = AnyReader([self.path], default_typestore=get_typestore(Stores.ROS2_HUMBLE))
            self._reader.open()
        except Exception as exc:  # noqa: BLE001 - rosbags raises many kinds for a damaged file
            raise BagError(f"could not read the bag {path}: {exc}") from None
        try:
            self._rig_topics = None if image_topics is None else self._camera_topics(image_topics)
            self._image = self._rig_topics[0] if image_topics else self._topic(image_topic, IMAGE_TYPES,
                                                                                "--image-topic", "images")
            self._odom = self._topic(odom_topic, (ODOM_TYPE,), "--odom-topic", "odometry")
            self._info = None if image_topics is not None else self._topic(
                info_topic, (INFO_TYPE,), "--camera-info-topic", "camera intrinsics", required=info_topic is not None)
            self._odometry = self._read_odometry()
            self.camera_info = self._read_info() if self._info else None
        except BagError:
            self.close()
            raise

    def close(self) -> None:
        self._reader.close()

    def __len__(self) -> int:
        return max(sum(c.msgcount for c in self._reader.connections if c.topic == topic)
                   for topic in (self._rig_topics or [self._image]))

    # ---- topics ------------------------------------------------------------
    def _topic(self, name: str | None, types: tuple[str, ...], option: str, what: str, required: bool = True):
        conns = self._reader.connections
        if name is not None:
            found = [c for c in conns if c.topic == name]
            if not found:
                raise BagError(f"the bag has no topic {name}; its topics: {self._listing()}")
            if found[0].msgtype not in types:
                raise BagError(f"topic {name} holds {found[0].msgtype}, not {' or '.join(types)}")
            return name
        topics = sorted({c.topic for c in conns if c.msgtype in types})
        if len(topics) == 1:
            return topics[0]
        if not topics:
            if required:
                raise BagError(f"the bag has no {what} topic ({' or '.join(types)}); its topics: {self._listing()}")
            return None
        raise BagError(f"the bag has {len(topics)} {what} topics ({', '.join(topics)}); name one with {option}")

    def _camera_topics(self, topics: list[str]) -> list[str]:
        """A rig's image topics, each checked (BagError naming the bag's
        image topics for one not given)."""
        if not all(topics):
            images = sorted({c.topic for c in self._reader.connections if c.msgtype in IMAGE_TYPES})
            raise BagError(f"camera {topics.index('')} of the rig has no image topic: give each camera's \"topic\" "
                           f"in the rig file or --topics T0,T1,... in the rig's order (the bag's image topics: "
                           f"{', '.join(images) or 'none'})")
        if len(set(topics)) != len(topics):
            raise BagError(f"the rig's cameras must have different image topics, got {', '.join(topics)}")
        return [self._topic(t, IMAGE_TYPES, "--topics", "images") for t in topics]

    def _listing(self) -> str:
        return ", ".join(sorted(f"{c.topic} ({c.msgtype})" for c in self._reader.connections)) or "none"

    def _messages(self, topic: str | list[str]):
        topics = [topic] if isinstance(topic, str) else topic
        conns = [c for c in self._reader.connections if c.topic in topics]
        for conn, bag_ns, raw in self._reader.messages(connections=conns):
            try:
                msg = self._reader.deserialize(raw, conn.msgtype)
            except Exception as exc:  # noqa: BLE001 - a damaged message is reported, not fatal
                yield conn, bag_ns, None, str(exc)
                continue
            yield conn, bag_ns, msg, ""

    # ---- odometry and intrinsics ------------------------------------------------
    def _read_odometry(self) -> tuple[list[float], list[tuple[float, float, float]]]:
        rows = []
        for _, bag_ns, msg, err in self._messages(self._odom):
            if msg is None:
                continue
            p, q = msg.pose.pose.position, msg.pose.pose.orientation
            yaw = math.degrees(math.atan2(2.0 * (q.w * q.z + q.x * q.y), 1.0 - 2.0 * (q.y * q.y + q.z * q.z)))
            row = (_stamp(msg, bag_ns), (float(p.x), float(p.y), yaw))
            if all(math.isfinite(v) for v in (row[0], *row[1])):
                rows.append(row)
        if not rows:
            raise BagError(f"the odometry topic {self._odom} holds no readable message")
        rows.sort(key=lambda r: r[0])
        return [r[0] for r in rows], [r[1] for r in rows]

    def camera(self, height_m: float | None, pitch_deg: float | None, roll_deg: float | None = None):
        """The camera of the intrinsics topic with the mounting the bag
        cannot hold: ``height_m`` above the floor, ``pitch_deg`` down,
        ``roll_deg`` the right side down."""
        from linemap.camera_files import camera_from_k

        if self.camera_info is None:
            raise BagError("the bag has no camera_info topic: give --camera (or --camera-k with --image-size)")
        if height_m is None:
            raise BagError("a camera from the bag's camera_info needs --height-m (metres above the floor)")
        i = self.camera_info
        return camera_from_k(i["k"], i["size"], height_m, pitch_deg or 0.0, i["distortion"], roll_deg=roll_deg)

    def _read_info(self) -> dict:
        for _, _, msg, _ in self._messages(self._info):
            if msg is None:
                continue
            k = np.asarray(getattr(msg, "k", getattr(msg, "K", None)), dtype=float).ravel()
            d = np.asarray(getattr(msg, "d", getattr(msg, "D", ())), dtype=float).ravel()
            if len(k) != 9 or not np.isfinite(k).all() or not np.isfinite(d).all():
                raise BagError(f"the camera_info topic {self._info}: K must be 9 finite numbers, got {k.tolist()}")
            return {"k": (k[0], k[4], k[2], k[5]), "size": (int(msg.width), int(msg.height)),
                    "distortion": tuple(d.tolist()) if d.any() else ()}
        raise BagError(f"the camera_info topic {self._info} holds no readable message")

    def odometry_at(self, t: float) -> tuple[float, float, float] | None:
        """The odometry at time ``t`` (seconds), linearly interpolated (the
        heading the short way round); None farther than ``max_gap_s`` from
        the messages on both sides."""
        ts, poses = self._odometry
        i = bisect.bisect_left(ts, t)
        if i < len(ts) and ts[i] == t:
            return poses[i]
        if i == 0 or i == len(ts):
            j = 0 if i == 0 else len(ts) - 1
            return poses[j] if abs(ts[j] - t) <= self.max_gap_s else None
        t0, t1 = ts[i - 1], ts[i]
        if t1 - t0 > 2 * self.max_gap_s and min(t - t0, t1 - t) > self.max_gap_s:
            return None
        a, b, w = poses[i - 1], poses[i], (t - t0) / (t1 - t0)
        return (a[0] + w * (b[0] - a[0]), a[1] + w * (b[1] - a[1]), wrap_deg(a[2] + w * wrap_deg(b[2] - a[2])))

    # ---- frames ------------------------------------------------------------
    def frames(self, detect) -> Iterator[FrameInput]:
        """A :class:`FrameInput` per image message, in the bag's order."""
        for number, (conn, bag_ns, msg, err) in enumerate(self._messages(self._image), 1):
            where = f"{self._image} message {number}"
            if msg is None:
                yield FrameInput(bag_ns * 1e-9, None, None, where, f"message could not be read ({err})")
                continue
            t = _stamp(msg, bag_ns)
            odom = self.odometry_at(t)
            if odom is None:
                yield FrameInput(t, None, None, where, f"no odometry within {self.max_gap_s:g} s of t={t:.3f} s")
                continue
            try:
                yield FrameInput(t, odom, detect(decode_image(msg, conn.msgtype)), where)
            except InputError as exc:
                yield FrameInput(t, odom, None, where, str(exc))

    def rig_frames(self, detect, settings=TRACKING) -> Iterator[FrameInput]:
        """A :class:`FrameInput` per instant of a rig's bag (the module
        docstring), its lines one set a camera: ``detect(image, k)``."""
        from matcher.tracking.rig_sync import instants, sync_tolerance

        topics = self._rig_topics
        tol = sync_tolerance([self._bag_times(topic, settings.rig_period_sample) for topic in topics], settings)
        stream = ((topics.index(conn.topic), bag_ns * 1e-9 if msg is None else _stamp(msg, bag_ns),
                   (conn, msg, err)) for conn, bag_ns, msg, err in self._messages(topics))
        for number, (t, items) in enumerate(instants(stream, len(topics), tol, settings), 1):
            where = f"instant {number} (t={t:.3f} s)"
            missing = [topic for topic, item in zip(topics, items) if item is None]
            odom = self.odometry_at(t)
            if missing:
                yield FrameInput(t, None, None, where, f"no image from {', '.join(missing)} within "
                                 f"{tol * 1e3:.0f} ms (half the slowest camera's frame period); an instant needs "
                                 "every camera")
            elif odom is None:
                yield FrameInput(t, None, None, where, f"no odometry within {self.max_gap_s:g} s of t={t:.3f} s")
            else:
                yield self._rig_frame(t, odom, where, items, detect)

    def _rig_frame(self, t: float, odom, where: str, items: list, detect) -> FrameInput:
        """The instant's frame: each camera's image decoded, its lines detected."""
        lines = []
        for k, (conn, msg, err) in enumerate(items):
            if msg is None:
                return FrameInput(t, odom, None, where, f"{conn.topic}: message could not be read ({err})")
            try:
                lines.append(detect(decode_image(msg, conn.msgtype), k))
            except InputError as exc:
                return FrameInput(t, odom, None, where, f"{conn.topic}: {exc}")
        return FrameInput(t, odom, lines, where)

    def _bag_times(self, topic: str, sample: int) -> list[float]:
        """The bag times (seconds) of the first ``sample`` messages of
        ``topic`` (read, not decoded)."""
        conns = [c for c in self._reader.connections if c.topic == topic]
        times = []
        for _, bag_ns, _ in self._reader.messages(connections=conns):
            times.append(bag_ns * 1e-9)
            if len(times) >= sample:
                break
        return times


def _stamp(msg, bag_ns: int) -> float:
    """The header's time stamp in seconds (the bag's receive time if it has none)."""
    stamp = getattr(getattr(msg, "header", None), "stamp", None)
    if stamp is None:
        return bag_ns * 1e-9
    sec = getattr(stamp, "sec", getattr(stamp, "secs", 0))
    nsec = getattr(stamp, "nanosec", getattr(stamp, "nsecs", 0))
    t = sec + nsec * 1e-9
    return t if t > 0 else bag_ns * 1e-9


def decode_image(msg, msgtype: str) -> np.ndarray:
    """The pixels of a ``sensor_msgs`` Image or CompressedImage; BagError
    for an encoding it cannot read."""
    import cv2

    data = np.asarray(msg.data, dtype=np.uint8)
    if msgtype.endswith("CompressedImage"):
        img = cv2.imdecode(data, cv2.IMREAD_GRAYSCALE)
        if img is None:
            raise BagError(f"compressed image ({msg.format or 'no format'}) could not be decoded")
        return img
    enc = msg.encoding.lower()
    channels = {"mono8": 1, "8uc1": 1, "bgr8": 3, "rgb8": 3, "8uc3": 3, "bgra8": 4, "rgba8": 4, "8uc4": 4,
                "mono16": 2, "16uc1": 2}.get(enc)
    if channels is None:
        raise BagError(f"image encoding {msg.encoding!r} is not supported (mono8, bgr8, rgb8, bgra8, rgba8, mono16)")
    h, w, step = int(msg.height), int(msg.width), int(msg.step)
    if step < w * channels or len(data) < h * step:
        raise BagError(f"image message is {len(data)} bytes, too short for {w}x{h} {msg.encoding}")
    rows = data[: h * step].reshape(h, step)[:, : w * channels]
    if channels == 2:
        px = rows.view(">u2" if msg.is_bigendian else "<u2").reshape(h, w)
        return (px >> 8).astype(np.uint8)
    img = rows.reshape(h, w, channels) if channels > 1 else rows
    return img
