"""The one room that knows ROS 2: the grounding agent on a robot.

What is here, one job per module:

* :mod:`~povagent.ros.extras`: the one-line stop when the ``ros`` or ``bags`` extra is missing,
  and the environment rclpy needs when it comes from PyPI;
* :mod:`~povagent.ros.transforms`: rigid transforms, quaternions, interpolation and the REP 103/105
  frame conventions (pure);
* :mod:`~povagent.ros.image_messages` and :mod:`~povagent.ros.camera_info`: ``sensor_msgs`` images and
  calibrations to RGB arrays, depth in metres and :class:`~povagent.geometry.goals.PinholeCamera` (pure);
* :mod:`~povagent.ros.tf_buffer`: ``/tf``, ``/tf_static`` and ``nav_msgs/Odometry`` to the camera's
  pose in the map at an image's stamp (pure);
* :mod:`~povagent.ros.keyframes`: the keyframe memory (which frames are kept, which is dropped)
  (pure), and :mod:`~povagent.ros.memory_folder`: saving it to a folder and loading it back;
* :mod:`~povagent.ros.session`: the one code path the node and the bag replay share: messages in,
  keyframes kept, a command answered into a :class:`~povagent.ros.result.CommandResult`
  (:mod:`~povagent.ros.result`: what ``~/result`` carries);
* :mod:`~povagent.ros.command_worker`: the node's answering, a bounded command queue and one
  worker thread giving every command one final result (pure: no ROS);
* :mod:`~povagent.ros.node` (rclpy) and :mod:`~povagent.ros.bag_replay` (rosbags): the two edges, and
  :mod:`~povagent.ros.spinning`: an executor spun in the background and stopped in the order rclpy
  requires (executor, node, context);
* :mod:`~povagent.ros.house_tour`: a generated house as a robot's recorded tour, written as a bag
  (:mod:`~povagent.ros.tour_bag`) or published live (:mod:`~povagent.ros.tour_player`);
* the node's parts: its camera subscriptions and their QoS (:mod:`~povagent.ros.camera_subscriptions`),
  its camera mount parameter (:mod:`~povagent.ros.camera_mount`), the frame its goals are in
  (:mod:`~povagent.ros.goal_frame`) and Nav2's ``navigate_to_pose`` action as the goal's way out
  (:mod:`~povagent.ros.navigate_action`).

Messages are read by their field names only (``msg.header.stamp.sec``, ``msg.encoding``, ``msg.k``),
so rclpy's message objects and rosbags' deserialized ones take the same path. Nothing outside the
ROS commands imports this package; the pure modules import neither rclpy nor rosbags.
"""
