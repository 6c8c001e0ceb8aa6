"""From an assembly problem to its system of rods: holds, links and bodies (issue 31;
docs/design.md, section 12).

Every rod is built as a single rod (:func:`~runtime.problem.assemble.build_model`, with
a node at each of its named points); the joints and bodies become the couplings of a
:class:`~runtime.model.system.SystemModel`:

* positions: the points that ``weld``, ``ball`` and ``hinge`` joints join form groups
  (union-find); a group with ``"ground"`` is held there (its nodes' rows are a support's),
  else its first node is the master and the others are tied to it. A group holding two
  supports (a rod's clamped or pinned end, or ground, twice) is redundant and refused;
* rotations: a ``weld`` is the rods' own elastic joint between the two points' frames (a
  weld of one rod's end to the next's start is exactly an interior joint of one rod): the
  half cells on either side in series, ``K = (sum_sides w C^-1)^-1`` with w = h/2 for a
  rod's end segment, 0 for a frame at an interior node (the two adjacent segments'
  frames summed: the slerp midpoint, at the node), the viscosity likewise
  (``materials.joint_series``); a ``hinge`` the same with its axis' stiffness replaced by
  ``rotational_stiffness`` (0 by default: free); a ``ball`` only its rotational spring,
  if given; a ``spring`` its 6x6 matrices between the two points' nodes and frames (or
  the ground's, fixed where the point is in the reference). To ground: a weld at a rod's
  end is a clamp (the end segment against the point's reference frame over half a
  segment); at an interior node it clamps both adjacent segments, each over its half
  segment, and the rod's own joint there is cut (the two halves are the joint's cell: a
  clamp in the middle of a rod, exact as a clamped end is);
* bodies: at their point's node, in the frame of the segment that follows the point
  (the last segment at a rod's end ``s = L``).

Where both sides of a weld are interior nodes of their rods (two rods crossing and welded),
the two frames are at the node and the weld has no half cell of its own: it gets a
quarter of each side's segment (an elastic weld of about a segment's length; first order
there, said in the joint's description).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np

from runtime.model.contact import SelfContactArrays
from runtime.model.quaternion import quat_mul, quat_rotation
from runtime.model.rod import RodModel
from runtime.model.system import Body, Hold, Link, Side, SystemModel
from runtime.problem.assemble import build_assembly_rod

_CONJ = np.array([1.0, -1.0, -1.0, -1.0])


@dataclass
class PointRef:
    """Where a named point is in the system: rod index, node, its frames (segments 1..N:
    one at a rod end, the two adjacent ones inside) and the half-cell weight of its frame
    (h/2 of the end segment; 0 at an interior node)."""

    rod: int
    node: int
    segments: tuple[int, ...]
    weight: float


@dataclass
class JointParts:
    """What joint k became: the holds and links it made (indices into the system's)."""

    holds: list[int] = field(default_factory=list)
    links: list[int] = field(default_factory=list)
    #: the point whose rod the reported force and moment act on, its hold (if any)
    first: PointRef | None = None
    note: str = ""


@dataclass
class AssemblyMap:
    """The system of an assembly and how its names map onto it."""

    model: SystemModel
    rod_names: list[str]
    joints: list[JointParts]
    points: dict[str, PointRef]

    def rod(self, name: str) -> int:
        return self.rod_names.index(name)


def _point_ref(rods: Sequence[RodModel], names: list[str], point) -> PointRef:
    r = names.index(point.rod)
    rod = rods[r]
    h = rod.arrays.seg_field("h")[:, 0]
    s_nodes = np.concatenate([[0.0], np.cumsum(h)])
    i = int(np.argmin(np.abs(s_nodes - point.s)))
    if i == 0:
        return PointRef(r, 0, (1,), 0.5 * float(h[0]))
    if i == rod.N:
        return PointRef(r, rod.N, (rod.N,), 0.5 * float(h[-1]))
    return PointRef(r, i, (i, i + 1), 0.0)


def _frame_sum(rod: RodModel, segs: tuple[int, ...], y: np.ndarray) -> np.ndarray:
    """The sum of the segments' quaternions (same hemisphere as the first)."""
    p = y[rod.p_index[segs[0] - 1]].copy()
    for sg in segs[1:]:
        q = y[rod.p_index[sg - 1]]
        p = p + (q if np.dot(q, p) >= 0 else -q)
    return p


def _stiffness(rod: RodModel, joint: int) -> tuple[np.ndarray, np.ndarray]:
    """The rotational stiffness and viscosity (3x3, material) of the rod's joint at node
    ``joint``: at an interior node the rod's own (its two segments in series), at an end
    the end segment's (a free end's joint carries it: ``materials.joint_series``)."""
    a = rod.arrays
    if a.coupled:
        return (a.jntc_field("C_MM")[joint].reshape(3, 3).copy(),
                a.jntc_field("V_MM")[joint].reshape(3, 3).copy())
    return np.diag(a.jnt_field("C_M")[joint]), np.diag(a.jnt_field("V_M")[joint])


def _series(sides: list[tuple[float, np.ndarray, np.ndarray]]) -> tuple[np.ndarray, np.ndarray]:
    """K = (sum w C^-1)^-1, V = K (sum w C^-1 V C^-1) K over the sides (w, C, V)."""
    F = sum(w * np.linalg.inv(C) for w, C, _ in sides if w > 0)
    G = sum(w * np.linalg.inv(C) @ V @ np.linalg.inv(C) for w, C, V in sides if w > 0)
    K = np.linalg.inv(F)
    K = 0.5 * (K + K.T)
    V = K @ G @ K
    return K, 0.5 * (V + V.T)


def _block6(rot_K: np.ndarray, rot_V: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    K, V = np.zeros((6, 6)), np.zeros((6, 6))
    K[3:, 3:], V[3:, 3:] = rot_K, rot_V
    return K, V


class _Groups:
    """Union-find of node keys (rod, node); ``"ground"`` a key of its own."""

    def __init__(self) -> None:
        self.parent: dict = {}

    def find(self, a):
        self.parent.setdefault(a, a)
        while self.parent[a] != a:
            self.parent[a] = self.parent[self.parent[a]]
            a = self.parent[a]
        return a

    def union(self, a, b) -> None:
        ra, rb = self.find(a), self.find(b)
        if ra != rb:
            self.parent[rb] = ra


def build_system(assembly, backend: str = "auto") -> AssemblyMap:
    """The :class:`SystemModel` of an assembly problem (see the module docstring)."""
    from runtime.errors import ParameterError

    names = list(assembly.rods)
    built = [build_assembly_rod(assembly.rods[n], backend=backend) for n in names]
    rods = [rod for rod, _ in built]
    pairs = None
    contact = getattr(assembly, "contact", None)
    if contact is not None and contact.self_contact:
        # one set of pairs over every rod's segments: rod-rod and each rod's self-contact
        pairs = SelfContactArrays(np.concatenate([law.seg for _, law in built]),
                                  rod_segments=tuple(r.N for r in rods))
    y_ref = [r.reference for r in rods]
    points: dict[str, PointRef] = {}

    def ref(point) -> PointRef:
        if point.label not in points:
            points[point.label] = _point_ref(rods, names, point)
        return points[point.label]

    groups = _Groups()
    ground_pos: dict = {}
    links: list[Link] = []
    parts = [JointParts() for _ in assembly.joints]
    cut: list[tuple[int, int]] = []
    for k, jt in enumerate(assembly.joints):
        P = ref(jt.first)
        parts[k].first = P
        rodP = rods[P.rod]
        pa0 = _frame_sum(rodP, P.segments, y_ref[P.rod])
        if jt.kind == "spring":
            if jt.second is None:
                side_b = Side(point=tuple(y_ref[P.rod][rodP.phi_index[P.node]]),
                              frame=tuple(pa0 / np.linalg.norm(pa0)))
                r0 = quat_mul(pa0 * _CONJ, pa0 / np.linalg.norm(pa0))
            else:
                Q = ref(jt.second)
                rodQ = rods[Q.rod]
                side_b = Side(node=(Q.rod, Q.node),
                              frames=tuple((Q.rod, s) for s in Q.segments))
                r0 = quat_mul(pa0 * _CONJ, _frame_sum(rodQ, Q.segments, y_ref[Q.rod]))
            side_a = Side(node=(P.rod, P.node), frames=tuple((P.rod, s) for s in P.segments))
            parts[k].links.append(len(links))
            links.append(Link(side_a, side_b, np.asarray(jt.stiffness_matrix, float),
                              np.asarray(jt.viscosity_matrix, float), r0=tuple(r0)))
            continue
        # weld, ball, hinge: the positions are one
        keyP = (P.rod, P.node)
        if jt.second is None:
            groups.union("ground", keyP)
            ground_pos[keyP] = tuple(y_ref[P.rod][rodP.phi_index[P.node]])
        else:
            Q = ref(jt.second)
            groups.union(keyP, (Q.rod, Q.node))
        side_a = Side(frames=tuple((P.rod, s) for s in P.segments))
        CP, VP = _stiffness(rodP, P.node)
        axis_P = None
        if jt.kind == "hinge":
            R0 = quat_rotation(pa0 / np.linalg.norm(pa0))
            axis_P = R0.T @ np.asarray(jt.axis, dtype=float)
            axis_P /= np.linalg.norm(axis_P)

        def rotational(Kw: np.ndarray, Vw: np.ndarray, jt=jt, axis_P=axis_P):
            if jt.kind == "weld":
                return Kw, Vw
            k_rot = float(jt.rotational_stiffness or 0.0)
            c_rot = float(jt.rotational_viscosity or 0.0)
            if jt.kind == "ball":
                return k_rot * np.eye(3), c_rot * np.eye(3)
            n = axis_P[:, None]
            Pp = np.eye(3) - n @ n.T
            return Pp @ Kw @ Pp + k_rot * (n @ n.T), Pp @ Vw @ Pp + c_rot * (n @ n.T)

        if jt.second is None:
            if jt.kind == "ball" and not (jt.rotational_stiffness or jt.rotational_viscosity):
                continue
            if len(P.segments) == 2 and jt.kind == "weld":
                # a clamp inside the rod: both halves clamped, the rod's joint cut
                cut.append((P.rod, P.node))
                h = rodP.arrays.seg_field("h")[:, 0]
                for sg, other in zip(P.segments, (P.node - 1, P.node + 1), strict=True):
                    C1, V1 = _stiffness(rodP, other)        # that segment's own
                    w = 0.5 * float(h[sg - 1])
                    p0 = y_ref[P.rod][rodP.p_index[sg - 1]]
                    K, V = _block6(C1 / w, V1 / w)
                    parts[k].links.append(len(links))
                    links.append(Link(Side(frames=((P.rod, sg),)),
                                      Side(frame=tuple(p0 / np.linalg.norm(p0))), K, V,
                                      r0=tuple(quat_mul(p0 * _CONJ, p0 / np.linalg.norm(p0)))))
                continue
            w = P.weight if P.weight > 0 else 0.5 * float(rodP.arrays.seg_field("h")[
                P.segments[0] - 1, 0])
            Kw, Vw = CP / w, VP / w
            K3, V3 = rotational(Kw, Vw)
            K, V = _block6(K3, V3)
            frame = pa0 / np.linalg.norm(pa0)
            parts[k].links.append(len(links))
            links.append(Link(side_a, Side(frame=tuple(frame)), K, V,
                              r0=tuple(quat_mul(pa0 * _CONJ, frame))))
            if P.weight == 0:
                parts[k].note = ("a hinge or spring to ground inside a rod acts on the frame "
                                 "at the node over half a segment (first order there)")
            continue
        Q = ref(jt.second)
        rodQ = rods[Q.rod]
        pb0 = _frame_sum(rodQ, Q.segments, y_ref[Q.rod])
        r0 = quat_mul(pa0 * _CONJ, pb0)
        Rab = quat_rotation(r0 / np.linalg.norm(r0))         # Q's components -> P's
        CQ, VQ = _stiffness(rodQ, Q.node)
        CQ, VQ = Rab @ CQ @ Rab.T, Rab @ VQ @ Rab.T
        wP, wQ = P.weight, Q.weight
        if wP == 0.0 and wQ == 0.0:
            wP = 0.25 * float(rodP.arrays.seg_field("h")[P.segments[0] - 1, 0])
            wQ = 0.25 * float(rodQ.arrays.seg_field("h")[Q.segments[0] - 1, 0])
            parts[k].note = ("both points are inside their rods: the weld takes a quarter "
                             "segment on each side as its own length (first order there)")
        if jt.kind in ("weld", "hinge"):
            Kw, Vw = _series([(wP, CP, VP), (wQ, CQ, VQ)])
        else:
            Kw = Vw = np.zeros((3, 3))
        K3, V3 = rotational(Kw, Vw)
        if not (np.any(K3) or np.any(V3)):
            continue
        K, V = _block6(K3, V3)
        parts[k].links.append(len(links))
        links.append(Link(side_a, Side(frames=tuple((Q.rod, s) for s in Q.segments)), K, V,
                          r0=tuple(r0)))
    # the position groups: supports and ties
    holds: list[Hold] = []
    members: dict = {}
    for key in list(groups.parent):
        members.setdefault(groups.find(key), []).append(key)
    hold_of: dict = {}
    for keys in members.values():
        nodes = [k for k in keys if k != "ground"]
        grounded = "ground" in keys
        held_by_rod = [k for k in nodes if k[1] in rods[k[0]].held_nodes]
        if grounded + len(held_by_rod) > 1:
            which = ", ".join(f"{names[r]} node {i}" for r, i in held_by_rod)
            raise ParameterError("joints", which or "ground", "at most one support per joined "
                                 "point: a rod end that is clamped or pinned by its own "
                                 "start/end table and also joined to ground, or to another "
                                 "held end, is held twice (redundant); make one of them free")
        if grounded:
            for key in nodes:
                pos = ground_pos.get(key) or tuple(y_ref[key[0]][rods[key[0]].phi_index[key[1]]])
                hold_of[key] = len(holds)
                holds.append(Hold(key[0], key[1], None, pos))
            continue
        master = held_by_rod[0] if held_by_rod else nodes[0]
        for key in nodes:
            if key != master:
                hold_of[key] = len(holds)
                holds.append(Hold(key[0], key[1], master))
    for k, jt in enumerate(assembly.joints):
        if jt.kind == "spring":
            continue
        for pt in (jt.first, jt.second):
            if pt is None:
                continue
            R = points[pt.label]
            h = hold_of.get((R.rod, R.node))
            if h is not None and h not in parts[k].holds:
                parts[k].holds.append(h)
    for r, node in cut:                                   # clamps inside a rod
        a = rods[r].arrays
        a.jnt_field("C_M")[node] = 0.0
        a.jnt_field("V_M")[node] = 0.0
        if a.coupled:
            a.jntc_field("C_MM")[node] = 0.0
            a.jntc_field("V_MM")[node] = 0.0
    bodies = []
    for b in assembly.bodies:
        P = ref(b.at)
        seg = P.segments[-1] if len(P.segments) == 1 else P.segments[1]
        bodies.append(Body(P.rod, P.node, seg, float(b.mass), np.asarray(b.inertia, float),
                           tuple(float(v) for v in b.offset)))
    gravity = _gravity(assembly)
    model = SystemModel(rods, names, holds, links, bodies, gravity=gravity, pairs=pairs)
    return AssemblyMap(model, names, parts, points)


def _gravity(assembly):
    loads = [ld for ld in assembly.gravity_loads()]
    if not loads:
        return None

    def g(t: float, left: bool, scale: float) -> np.ndarray:
        out = np.zeros(3)
        for ld in loads:
            out += np.asarray(ld.vector, dtype=float) * ld.time.value_at(t, left=left)
        return scale * out

    return g


def frames_of(model: SystemModel, rod: int, segs: tuple[int, ...], y: np.ndarray) -> np.ndarray:
    """The frame (3x3) of a point from its segments at state y."""
    p = _frame_sum(model.rods[rod], segs, model.rod_state(rod, y))
    return quat_rotation(p / np.linalg.norm(p))
