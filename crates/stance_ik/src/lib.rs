//! Kinematics and the prioritized damped least-squares IK solver of Stance.
