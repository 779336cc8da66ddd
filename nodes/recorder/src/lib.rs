//! recorder: MCAP recording (ROS 2 profile) of every suite topic, recovery and replay.
