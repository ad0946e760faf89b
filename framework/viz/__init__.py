"""What people look at: what to draw of a robot (links, joints, URDF visuals) and the meshcat viewer."""
