"""Robot files to a :class:`~framework.model.robot.Robot`: URDF / xacro loading, floating bases, DH tables,
mounting arms on bases, joint kinds, and the compiled kinematics read from the Pinocchio model."""
