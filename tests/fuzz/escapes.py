"""Escape attempts from a robot file (xacro is data: each must fail with our error and no side effect), and
the small xacro arm they are put into (``EXTRA`` marks the place). Read by ``tests/test_xacro_files.py`` and
``benchmarks/reliability.py``."""

ARM = """<?xml version="1.0"?>
<robot name="arm" xmlns:xacro="http://www.ros.org/wiki/xacro">
  <xacro:arg name="length" default="0.3"/>
  <xacro:property name="L" value="$(arg length)"/>
  <xacro:property name="half" value="${L / 2}"/>
  <link name="base"/>
  <link name="tip"/>
  <joint name="j1" type="revolute">
    <parent link="base"/><child link="tip"/>
    <origin xyz="0 0 ${max(half, 0.1) * 2}" rpy="0 0 ${math.pi / 4 + radians(0)}"/>
    <axis xyz="0 0 1"/><limit lower="${-pi}" upper="${pi}" effort="1" velocity="1"/>
  </joint>
  EXTRA
</robot>
"""

ESCAPES = {
    "subclasses walk": "${python.type.mro(python.type)[1].__subclasses__()}",
    "vars string key": "${python.vars(python.type)['__subcl' + 'asses__']}",
    # xacro's own evaluator accepts this one (255 subclasses of object: the road to os.system)
    "subclasses via vars": "${len(python.vars(python.type)['__subclasses__'](python.type.mro(python.type)[1]))}",
    "class attribute": "${(1).__class__}",
    "str format": "${'{0.__class__}'.format(1)}",
    "open": "${open('/etc/passwd').read()}",
    "eval": "${eval('1')}",
    "getattr": "${getattr(1, 'real')}",
    "lambda": "${(lambda: 1)()}",
    "comprehension": "${[c for c in 'ab']}",
    "import": "${__import__('os')}",
    "load_yaml": "${xacro.load_yaml('/etc/hostname')}",
    "direct load_yaml": "${load_yaml('/etc/hostname')}",
    "env": "$(env HOME)",
    "optenv": "$(optenv HOME nothing)",
    "eval substitution": "$(eval 1 + 1)",
}
