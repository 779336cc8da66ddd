//! tyre_msgs: the Rust side of the `tyre_msgs` ROS 2 interface package (see `msg/`).
