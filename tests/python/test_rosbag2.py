"""Issue 40: semap.open_dataset reads a rosbag2 SQLite3 bag (.db3) as the CLI does. The bag is
written here with Python's sqlite3 and a small CDR (XCDR1, little endian) encoder, following
rosbag2's published Humble schema and the sensor_msgs/msg definitions, from a synthetic folder
dataset; it must read back frame for frame like the folder."""
import sqlite3
import struct
import subprocess

import numpy as np
import pytest

import semap
from conftest import BUILD


class Cdr:
    """CDR encoder: 4-byte encapsulation header (CDR_LE), alignment counted after it."""

    def __init__(self):
        self.buf = bytearray(b"\x00\x01\x00\x00")

    def _align(self, n):
        while (len(self.buf) - 4) % n:
            self.buf.append(0)

    def u8(self, v):
        self.buf += struct.pack("<B", v)

    def u32(self, v):
        self._align(4)
        self.buf += struct.pack("<I", v)

    def i32(self, v):
        self._align(4)
        self.buf += struct.pack("<i", v)

    def f64(self, v):
        self._align(8)
        self.buf += struct.pack("<d", v)

    def string(self, s):
        data = s.encode() + b"\x00"
        self.u32(len(data))
        self.buf += data

    def octets(self, data):
        self.u32(len(data))
        self.buf += data

    def header(self, stamp_ns, frame_id):
        self.i32(stamp_ns // 1_000_000_000)
        self.u32(stamp_ns % 1_000_000_000)
        self.string(frame_id)


def image_message(stamp_ns, array, encoding):
    m = Cdr()
    m.header(stamp_ns, "camera")
    m.u32(array.shape[0])
    m.u32(array.shape[1])
    m.string(encoding)
    m.u8(0)  # is_bigendian
    m.u32(array.strides[0])
    m.octets(np.ascontiguousarray(array).tobytes())
    return bytes(m.buf)


def camera_info_message(stamp_ns, camera):
    m = Cdr()
    m.header(stamp_ns, "camera")
    m.u32(camera.height)
    m.u32(camera.width)
    m.string("plumb_bob")
    m.u32(5)
    for d in (0.0,) * 5:
        m.f64(d)
    for k in (camera.fx, 0.0, camera.cx, 0.0, camera.fy, camera.cy, 0.0, 0.0, 1.0):
        m.f64(k)
    for r in (1.0, 0, 0, 0, 1.0, 0, 0, 0, 1.0):  # R
        m.f64(r)
    for p in (camera.fx, 0.0, camera.cx, 0.0, 0.0, camera.fy, camera.cy, 0.0, 0.0, 0.0, 1.0, 0.0):  # P
        m.f64(p)
    for v in (0, 0, 0, 0, 0, 0):  # binning_x, binning_y, roi x, y, height, width
        m.u32(v)
    m.u8(0)  # roi.do_rectify
    return bytes(m.buf)


def write_db3(path, folder):
    """rosbag2's Humble SQLite3 schema: topics + messages (timestamp: receive time, ns)."""
    db = sqlite3.connect(path)
    db.execute("CREATE TABLE topics(id INTEGER PRIMARY KEY, name TEXT NOT NULL, type TEXT NOT NULL, "
               "serialization_format TEXT NOT NULL, offered_qos_profiles TEXT NOT NULL)")
    db.execute("CREATE TABLE messages(id INTEGER PRIMARY KEY, topic_id INTEGER NOT NULL, "
               "timestamp INTEGER NOT NULL, data BLOB NOT NULL)")
    topics = [("/camera/color/image_raw", "sensor_msgs/msg/Image"),
              ("/camera/color/camera_info", "sensor_msgs/msg/CameraInfo"),
              ("/camera/depth/image_rect_raw", "sensor_msgs/msg/Image"),
              ("/camera/depth/camera_info", "sensor_msgs/msg/CameraInfo")]
    for i, (name, kind) in enumerate(topics, start=1):
        db.execute("INSERT INTO topics VALUES (?, ?, ?, 'cdr', '')", (i, name, kind))
    for f in folder:
        stamp_ns = int(round(f.timestamp * 1e9))
        depth = np.where(f.depth > 0, f.depth, np.nan).astype(np.float32)  # 32FC1: NaN = no depth
        for topic_id, data in ((1, image_message(stamp_ns, f.rgb, "rgb8")),
                               (2, camera_info_message(stamp_ns, folder.camera)),
                               (3, image_message(stamp_ns, depth, "32FC1")),
                               (4, camera_info_message(stamp_ns, folder.camera))):
            db.execute("INSERT INTO messages(topic_id, timestamp, data) VALUES (?, ?, ?)", (topic_id, stamp_ns + 1000, data))
    db.commit()
    db.close()


@pytest.fixture(scope="module")
def folder_and_bag(tmp_path_factory):
    tmp = tmp_path_factory.mktemp("rosbag2")
    subprocess.run([str(BUILD / "semap"), "synth", "--out", str(tmp / "data"), "--frames", "6", "--objects", "2",
                    "--width", "160", "--height", "120", "--seed", "4"], check=True, capture_output=True)
    folder = semap.open_dataset(tmp / "data")
    write_db3(tmp / "recording.db3", folder)
    return folder, tmp / "recording.db3"


def test_db3_reads_back_like_the_folder(folder_and_bag):
    folder, bag_path = folder_and_bag
    bag = semap.open_dataset(bag_path)
    assert len(bag) == len(folder) == 6
    for key in ("fx", "fy", "cx", "cy", "width", "height"):
        assert getattr(bag.camera, key) == pytest.approx(getattr(folder.camera, key))
    assert bag.timestamps == pytest.approx(folder.timestamps, abs=1e-6)
    for i in range(len(folder)):
        np.testing.assert_array_equal(bag[i].rgb, folder[i].rgb)
        np.testing.assert_array_equal(bag[i].depth, folder[i].depth)


def test_cut_database_is_a_semap_error(folder_and_bag, tmp_path):
    _, bag_path = folder_and_bag
    cut = tmp_path / "cut.db3"
    cut.write_bytes(bag_path.read_bytes()[:4096])
    with pytest.raises(semap.Error, match="cut.db3"):
        ds = semap.open_dataset(cut)
        for f in ds:
            pass
