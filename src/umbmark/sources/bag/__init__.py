"""ROS bags: wheel rotation, ground truth, laser scans and an IMU's gyro from ROS 1 and
ROS 2 recordings, and what a bag holds.

Modules by concern, lowest first; a module imports only from those above it in this list
(and from :mod:`umbmark.core`, :mod:`umbmark.model`, :mod:`umbmark.sources.text` and
:mod:`umbmark.sources.progress`):

1. What things are called: :mod:`~umbmark.sources.bag.msgtypes` (message types, the
   transform topics, the fields the readers use), :mod:`~umbmark.sources.bag.names`
   (what names say: left and right, ground truth, fixed frames),
   :mod:`~umbmark.sources.bag.fieldpath` (paths to a value in a message of any type).
2. :mod:`~umbmark.sources.bag.bag_options`: what to read (``BagOptions``) and its checks.
3. The files: :mod:`~umbmark.sources.bag.reader` (opening bags, topics, raw messages,
   the time windows of a long recording; every rosbags failure one line),
   :mod:`~umbmark.sources.bag.writer` (writing one) and
   :mod:`~umbmark.sources.bag.imu_writer` (an IMU's track and messages, for it).
4. Messages to samples: :mod:`~umbmark.sources.bag.fastpath` (the byte-level decoder),
   :mod:`~umbmark.sources.bag.samples` (a topic's samples, times, cleaning),
   :mod:`~umbmark.sources.bag.custom` (definitions of custom message types),
   :mod:`~umbmark.sources.bag.scans` (a laser's sweeps, ``sensor_msgs/LaserScan``).
5. Side by side, neither importing the other: :mod:`umbmark.sources.bag.wheels` (joint
   states, encoder ticks and fields, wheel frames on ``/tf``, the controller's odometry
   turned back into wheel rotation) and :mod:`umbmark.sources.bag.truth` (pose topics,
   transform chains, Gazebo's model states and position-only references, and the checks
   that a ground truth is not the odometry).
6. :mod:`~umbmark.sources.bag.recording`: ``read_recording`` and ``read_bag``, the
   options turned into wheels, ground truth and notes.
7. :mod:`~umbmark.sources.bag.urdf`: the wheel geometry and the fixed joints of a
   recorded robot description; :mod:`~umbmark.sources.bag.imu_frames` (an IMU frame's
   mounting in the base frame, from ``/tf_static``, ``/tf`` or the description) and
   :mod:`~umbmark.sources.bag.imu` (an IMU's gyro in the base frame, ``sensor_msgs/Imu``).
8. :mod:`umbmark.sources.bag.info`: what ``umbmark info`` reports (the bounded scan of
   the topics, the transforms and their chains, the candidates for each input).

``tests/test_bag_layout.py`` holds the order.

rosbags is imported only when a bag is opened or written.
"""
