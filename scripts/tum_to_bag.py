#!/usr/bin/python3
"""Writes a TUM RGB-D folder as a ROS1 bag laid out as TUM's own bags: /camera/rgb/image_color
(rgb8) and /camera/depth/image (32FC1 metres, NaN where there is no measurement), each message
stamped with its image's time. Needs Debian's python3-rosbag, python3-sensor-msgs and
python3-opencv; independent of noctua, so that noctua's bag reader is checked against another
program's bags.

    scripts/tum_to_bag.py FOLDER OUT.bag [--frames N] [--depth-factor 5000]
"""
import argparse
import pathlib
import sys

try:
    import cv2
    import numpy
    import rosbag
    import rospy
    from sensor_msgs.msg import Image
except ImportError as error:
    sys.exit(f"tum_to_bag: {error} (Debian: apt-get install python3-rosbag python3-sensor-msgs "
             "python3-opencv)")


def read_list(path):
    """(timestamp, file) of a TUM list, comments skipped."""
    entries = []
    for line in path.read_text().splitlines():
        if line.startswith("#") or not line.strip():
            continue
        stamp, name = line.split()[:2]
        entries.append((float(stamp), name))
    return entries


def image_message(pixels, encoding, stamp, seq):
    message = Image()
    message.header.seq = seq
    message.header.stamp = rospy.Time.from_sec(stamp)
    message.header.frame_id = "/openni_rgb_optical_frame"
    message.height, message.width = pixels.shape[:2]
    message.encoding = encoding
    message.is_bigendian = 0
    message.step = pixels.strides[0]
    message.data = pixels.tobytes()
    return message


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("folder", type=pathlib.Path)
    parser.add_argument("bag", type=pathlib.Path)
    parser.add_argument("--frames", type=int, default=0, help="first N colour images (0: all)")
    parser.add_argument("--depth-factor", type=float, default=5000.0)
    args = parser.parse_args()
    rgb = read_list(args.folder / "rgb.txt")
    if args.frames > 0:
        rgb = rgb[:args.frames]
    # The depth images up to the last colour image's time, as a recording cut there would hold.
    depth = [d for d in read_list(args.folder / "depth.txt") if d[0] <= rgb[-1][0] + 0.02]
    messages = [(s, f, "/camera/rgb/image_color") for s, f in rgb]
    messages += [(s, f, "/camera/depth/image") for s, f in depth]
    messages.sort()
    with rosbag.Bag(str(args.bag), "w") as bag:
        for seq, (stamp, name, topic) in enumerate(messages):
            path = str(args.folder / name)
            if topic.endswith("image_color"):
                pixels = cv2.cvtColor(cv2.imread(path, cv2.IMREAD_COLOR), cv2.COLOR_BGR2RGB)
                message = image_message(pixels, "rgb8", stamp, seq)
            else:
                raw = cv2.imread(path, cv2.IMREAD_UNCHANGED)
                metres = raw.astype(numpy.float32) / args.depth_factor
                metres[raw == 0] = numpy.nan
                message = image_message(metres, "32FC1", stamp, seq)
            bag.write(topic, message, rospy.Time.from_sec(stamp))
    print(f"tum_to_bag: {len(rgb)} colour and {len(depth)} depth images in {args.bag}")


if __name__ == "__main__":
    main()
