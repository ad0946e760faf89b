"""Random URDF trees for property tests: every joint type we solve (revolute, continuous, prismatic, fixed), axes
along ±x/±y/±z or oblique, placements with arbitrary rotations, one joint or many, branches, and mimic joints
(a ``<mimic>`` of an earlier joint, with a multiplier and an offset).

``random_tree(rng)`` is plain numpy (a benchmark draws hundreds); ``trees()`` is the hypothesis strategy of the
same trees, drawn from a seed so that a failing example shrinks to a seed one can replay."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

KINDS = ("revolute", "continuous", "prismatic", "fixed")


@dataclass(frozen=True)
class Tree:
    """A random robot: its URDF, its solved joint names, its mimic joints (name -> (leader, multiplier,
    offset)) and its leaf links."""

    urdf: str
    movable: tuple[str, ...]
    leaves: tuple[str, ...]
    seed: int
    mimic: dict = field(default_factory=dict)


def _axis(rng: np.random.Generator) -> np.ndarray:
    if rng.random() < 0.5:  # a principal axis, either sign (most URDFs)
        axis = np.zeros(3)
        axis[rng.integers(3)] = rng.choice([-1.0, 1.0])
        return axis
    axis = rng.normal(size=3)
    return axis / np.linalg.norm(axis)


def random_tree(rng: np.random.Generator | int, *, joints: tuple[int, int] = (1, 8),
                branch: float = 0.3, fixed: float = 0.15, mimic: float = 0.1) -> Tree:
    """A random tree of ``joints`` (min, max) solved joints; each new link hangs from the last one (a chain) or,
    with probability ``branch``, from any earlier link; a fraction ``fixed`` of extra fixed joints and a fraction
    ``mimic`` of extra joints mimicking an earlier solved revolute or prismatic joint."""
    seed = int(rng) if not isinstance(rng, np.random.Generator) else int(rng.integers(2**31))
    rng = np.random.default_rng(seed)
    count = int(rng.integers(joints[0], joints[1] + 1))
    links, lines, movable = ["l0"], [], []
    children: dict[str, int] = {"l0": 0}
    mimics: dict[str, tuple[str, float, float]] = {}
    kinds: dict[str, str] = {}
    while len(movable) < count:
        kind = "fixed" if rng.random() < fixed else str(rng.choice(KINDS[:3], p=[0.6, 0.2, 0.2]))
        leaders = [j for j in movable if kinds[j] in ("revolute", "prismatic")]
        follow = kind != "fixed" and leaders and rng.random() < mimic
        parent = links[-1] if rng.random() > branch else links[int(rng.integers(len(links)))]
        child = f"l{len(links)}"
        xyz = rng.uniform(-0.3, 0.3, 3)
        rpy = rng.uniform(-np.pi, np.pi, 3)
        axis = _axis(rng)
        name = f"j{len(links)}"
        limit = ""
        if kind == "revolute":
            limit = f'<limit lower="{rng.uniform(-np.pi, -0.5):.6f}" upper="{rng.uniform(0.5, np.pi):.6f}" ' \
                    'effort="1" velocity="1"/>'
        elif kind == "prismatic":
            limit = f'<limit lower="{rng.uniform(-0.4, -0.05):.6f}" upper="{rng.uniform(0.05, 0.4):.6f}" ' \
                    'effort="1" velocity="1"/>'
        if follow:
            leader = leaders[int(rng.integers(len(leaders)))]
            multiplier, offset = round(float(rng.uniform(-1.5, 1.5)), 6), round(float(rng.uniform(-0.3, 0.3)), 6)
            mimics[name] = (leader, multiplier, offset)
            limit += f'<mimic joint="{leader}" multiplier="{multiplier}" offset="{offset}"/>'
        lines.append(
            f'<joint name="{name}" type="{kind}"><parent link="{parent}"/><child link="{child}"/>'
            f'<origin xyz="{" ".join(f"{v:.6f}" for v in xyz)}" rpy="{" ".join(f"{v:.6f}" for v in rpy)}"/>'
            f'<axis xyz="{" ".join(f"{v:.9f}" for v in axis)}"/>{limit}</joint>'
        )
        links.append(child)
        children[parent] = children.get(parent, 0) + 1
        children[child] = 0
        kinds[name] = kind
        if kind != "fixed" and not follow:
            movable.append(name)
    body = "".join(f'<link name="{link}"/>' for link in links) + "".join(lines)
    leaves = tuple(link for link in links if children[link] == 0)
    return Tree(f'<robot name="tree{seed}">{body}</robot>', tuple(movable), leaves, seed, mimics)


def trees(**kwargs):
    """The hypothesis strategy of :func:`random_tree` (drawn by seed)."""
    from hypothesis import strategies as st

    return st.integers(0, 2**31 - 1).map(lambda seed: random_tree(seed, **kwargs))
