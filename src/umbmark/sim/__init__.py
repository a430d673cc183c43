"""The virtual robot: closed-loop UMBmark runs on robots whose errors we choose.

The controller steers by the robot's **own odometry**, as a real robot does; the true
motion is integrated exactly. That is what makes the return errors appear.
"""
