r"""Compiled clearance of a sphere model, certified motions and RRT-Connect.

The robot and the scene come packed in arrays by
:class:`workbench.motion.checker.SphereChecker` (its docstring names them);
this module only computes.

**Clearance.** At a configuration every link gets a lower bound of its
distance to the scene (every obstacle it is not allowed to touch) and every
checked link pair one of its distance: first from the link's bounding sphere,
then, where that bound is below what the caller needs, from the link's own
spheres (each inside the bounding sphere, so never nearer), visited by groups
of near spheres: a group whose bounding sphere is no nearer than the nearest
sphere so far, or already shows the need, is skipped (its bound kept). A need
the spheres cannot show (beyond the bound plus twice the radius,
:func:`_limit`) is not refined for; they are visited only for contacts.
Signed distances
of a sphere centre to boxes, cylinders and spheres are exact; to a mesh it is
the unsigned distance to its triangles.

**Allowances.** Each entry may carry an allowance [m] added to its
clearance: the spheres may overlap by that much (where they overlap at the
start or goal while the exact meshes are apart) and no more. A link's
allowance against the scene is held per obstacle (``lallow[l, o]``: the
fingers may overlap the object they grasp, not the shelf beside it). A pair with a
table (:mod:`workbench.motion.pair_tables`) takes the table's clearance at
the node nearest to its one or two relative joints (:func:`_table_clearance`)
instead of its spheres', where its meshes are apart at that node.

**Certified motions.** Along the straight joint segment from
:math:`q_a` to :math:`q_b` a point of link :math:`l` moves by at most
:math:`D_l = \sum_i L_{l,i} |\Delta q_i|` (lever arms, as in
:mod:`workbench.collision.checker`), and a pair's distance changes by at most
:math:`D_a + D_b`. With clearances :math:`c_0, c_1` at the two ends of a
sub-interval of length :math:`w` (as a fraction of the segment), every point
of it is free when :math:`c_0 + c_1 \ge D w`; otherwise the interval is
bisected. A segment is accepted only when every sub-interval is so proven,
and refused as soon as a clearance is negative or an interval's motion bound
falls below :data:`RESOLUTION` unproven: no contact of the spheres is missed,
however thin the obstacle.
"""

from __future__ import annotations

import math

import numpy as np
import numpy.typing as npt

from workbench._compiled import entry_point, helper

FloatArray = npt.NDArray[np.float64]
IntArray = npt.NDArray[np.int64]
BoolArray = npt.NDArray[np.bool_]

#: An interval whose motion bound is below this [m] and is still unproven
#: counts as a contact.
RESOLUTION = 1e-4
#: Most clearance evaluations of one segment before it is refused.
MAX_EVALUATIONS = 512
#: The packed arrays every entry point takes, C-contiguous (reshaped inside).
_PACKED = ("levers", "robot_int", "robot_float", "scene_int", "scene_float", "tris")
#: Obstacle kinds.
BOX, CYLINDER, SPHERE, MESH = 0, 1, 2, 3


@helper(forceinline=True)
def _frames(
    q: FloatArray,
    jparent: IntArray,
    jrot: FloatArray,
    jpos: FloatArray,
    jaxis: FloatArray,
    jq: IntArray,
    orot: FloatArray,
    opos: FloatArray,
) -> None:
    """Joint frames (J, 3, 3), (J, 3) in the base frame at q (revolute joints)."""
    orot[0] = np.eye(3)
    opos[0] = 0.0
    r = np.empty((3, 3))
    placed = np.empty((3, 3))
    for j in range(1, len(jparent)):
        p = jparent[j]
        angle = q[jq[j]]
        c, s = math.cos(angle), math.sin(angle)
        x, y, z = jaxis[j, 0], jaxis[j, 1], jaxis[j, 2]
        t = 1.0 - c
        r[0, 0], r[0, 1], r[0, 2] = c + x * x * t, x * y * t - z * s, x * z * t + y * s
        r[1, 0], r[1, 1], r[1, 2] = y * x * t + z * s, c + y * y * t, y * z * t - x * s
        r[2, 0], r[2, 1], r[2, 2] = z * x * t - y * s, z * y * t + x * s, c + z * z * t
        for a in range(3):
            for b in range(3):
                placed[a, b] = (
                    orot[p, a, 0] * jrot[j, 0, b]
                    + orot[p, a, 1] * jrot[j, 1, b]
                    + orot[p, a, 2] * jrot[j, 2, b]
                )
        for a in range(3):
            for b in range(3):
                orot[j, a, b] = (
                    placed[a, 0] * r[0, b]
                    + placed[a, 1] * r[1, b]
                    + placed[a, 2] * r[2, b]
                )
        _place(orot[p], opos[p], jpos[j], opos[j])


@helper(forceinline=True)
def _place(
    rot: FloatArray, pos: FloatArray, local: FloatArray, out: FloatArray
) -> None:
    """Set out = rot @ local + pos, for (3, 3), (3,), (3,) and (3,) arrays."""
    for i in range(3):
        out[i] = (
            rot[i, 0] * local[0] + rot[i, 1] * local[1] + rot[i, 2] * local[2] + pos[i]
        )


@helper(forceinline=True)
def _norm(x: float, y: float, z: float) -> float:
    """Length of the vector (x, y, z)."""
    return math.sqrt(x * x + y * y + z * z)


@helper(forceinline=True)
def _gap(a: FloatArray, b: FloatArray) -> float:
    """Distance [m] between two points (3,)."""
    return _norm(a[0] - b[0], a[1] - b[1], a[2] - b[2])


@helper(forceinline=True)
def _point_triangle(px: float, py: float, pz: float, tri: FloatArray) -> float:
    """Distance [m] from point p to the triangle tri (3, 3) (Ericson, 5.1.5).

    In scalars: array temporaries would allocate, and their cleanup slows
    every caller that inlines this, whether or not it reaches a mesh.
    """
    ax, ay, az = tri[0, 0], tri[0, 1], tri[0, 2]
    abx, aby, abz = tri[1, 0] - ax, tri[1, 1] - ay, tri[1, 2] - az
    acx, acy, acz = tri[2, 0] - ax, tri[2, 1] - ay, tri[2, 2] - az
    apx, apy, apz = px - ax, py - ay, pz - az
    d1 = abx * apx + aby * apy + abz * apz
    d2 = acx * apx + acy * apy + acz * apz
    if d1 <= 0.0 and d2 <= 0.0:
        return _norm(apx, apy, apz)
    bpx, bpy, bpz = apx - abx, apy - aby, apz - abz
    d3 = abx * bpx + aby * bpy + abz * bpz
    d4 = acx * bpx + acy * bpy + acz * bpz
    if d3 >= 0.0 and d4 <= d3:
        return _norm(bpx, bpy, bpz)
    vc = d1 * d4 - d3 * d2
    if vc <= 0.0 and d1 >= 0.0 and d3 <= 0.0:
        v = d1 / (d1 - d3)
        return _norm(apx - v * abx, apy - v * aby, apz - v * abz)
    cpx, cpy, cpz = apx - acx, apy - acy, apz - acz
    d5 = abx * cpx + aby * cpy + abz * cpz
    d6 = acx * cpx + acy * cpy + acz * cpz
    if d6 >= 0.0 and d5 <= d6:
        return _norm(cpx, cpy, cpz)
    vb = d5 * d2 - d1 * d6
    if vb <= 0.0 and d2 >= 0.0 and d6 <= 0.0:
        w = d2 / (d2 - d6)
        return _norm(apx - w * acx, apy - w * acy, apz - w * acz)
    va = d3 * d6 - d5 * d4
    if va <= 0.0 and (d4 - d3) >= 0.0 and (d5 - d6) >= 0.0:
        w = (d4 - d3) / ((d4 - d3) + (d5 - d6))
        # p - (b + w (c - b)) = bp - w (ac - ab)
        return _norm(
            bpx - w * (acx - abx), bpy - w * (acy - aby), bpz - w * (acz - abz)
        )
    denom = 1.0 / (va + vb + vc)
    v, w = vb * denom, vc * denom
    return _norm(
        apx - abx * v - acx * w, apy - aby * v - acy * w, apz - abz * v - acz * w
    )


@helper(forceinline=True)
def _distance(
    p: FloatArray,
    o: int,
    okind: IntArray,
    orot: FloatArray,
    opos: FloatArray,
    osize: FloatArray,
    ofirst: IntArray,
    tris: FloatArray,
    best: float,
) -> float:
    """Signed distance [m] from point p to obstacle o (meshes: unsigned).

    For a mesh, returns early with a value >= ``best`` when its bounding
    sphere is farther than ``best``.
    """
    dx, dy, dz = p[0] - opos[o, 0], p[1] - opos[o, 1], p[2] - opos[o, 2]
    r = orot[o]
    lx = r[0, 0] * dx + r[1, 0] * dy + r[2, 0] * dz
    ly = r[0, 1] * dx + r[1, 1] * dy + r[2, 1] * dz
    lz = r[0, 2] * dx + r[1, 2] * dy + r[2, 2] * dz
    kind = okind[o]
    if kind == BOX:
        ox = abs(lx) - osize[o, 0]
        oy = abs(ly) - osize[o, 1]
        oz = abs(lz) - osize[o, 2]
        outside = math.sqrt(max(ox, 0.0) ** 2 + max(oy, 0.0) ** 2 + max(oz, 0.0) ** 2)
        return outside + min(max(ox, max(oy, oz)), 0.0)
    if kind == CYLINDER:
        radial = math.sqrt(lx * lx + ly * ly) - osize[o, 0]
        axial = abs(lz) - osize[o, 1]
        outside = math.sqrt(max(radial, 0.0) ** 2 + max(axial, 0.0) ** 2)
        return outside + min(max(radial, axial), 0.0)
    if kind == SPHERE:
        return _norm(dx, dy, dz) - osize[o, 0]
    bound = _norm(dx, dy, dz) - osize[o, 0]
    if bound >= best:
        return bound
    out = math.inf
    for t in range(ofirst[o], ofirst[o + 1]):
        out = min(out, _point_triangle(lx, ly, lz, tris[t]))
    return out


@helper(forceinline=True)
def _place_once(
    rot: FloatArray,
    pos: FloatArray,
    k: int,
    first: IntArray,
    placed: BoolArray,
    local: FloatArray,
    world: FloatArray,
) -> None:
    """Place points ``first[k]:first[k + 1]`` of ``local`` in ``world``, once.

    Used for a link's group centres (``k`` a link) and a group's spheres
    (``k`` a group); ``placed[k]`` records that it was done.
    """
    if not placed[k]:
        for s in range(first[k], first[k + 1]):
            _place(rot, pos, local[s], world[s])
        placed[k] = True


@helper(forceinline=True)
def _sphere_distance(
    center: FloatArray,
    radius: float,
    slack: float,
    o: int,
    okind: IntArray,
    orot: FloatArray,
    opos: FloatArray,
    osize: FloatArray,
    ofirst: IntArray,
    tris: FloatArray,
    best: float,
) -> float:
    """Distance [m] of a sphere to obstacle o plus ``slack`` (an allowance).

    A mesh's may return early with a value >= ``best`` (see :func:`_distance`).
    """
    return (
        _distance(
            center, o, okind, orot, opos, osize, ofirst, tris, best + radius - slack
        )
        - radius
        + slack
    )


@helper(forceinline=True)
def _limit(need: float, bound: float, radius: float) -> float:
    """How far to refine an entry whose bounding spheres show ``bound`` [m].

    Its spheres (inside bounding spheres of total radius ``radius``) are
    never more than ``bound + 2 radius`` clear, so a finite ``need`` beyond
    that cannot be shown: refine only to find contacts (0). An infinite
    ``need`` asks for the exact minimum.
    """
    if need == math.inf or need <= bound + 2.0 * radius:
        return need
    return 0.0


@helper(forceinline=True)
def _table_clearance(
    q: FloatArray,
    k: int,
    tstart: IntArray,
    tjoint: IntArray,
    tcells: IntArray,
    tperiodic: IntArray,
    tlower: FloatArray,
    tstep: FloatArray,
    tvalues: FloatArray,
) -> float:
    """Pair k's clearance [m] at q: its table's value at the nearest node.

    NaN for a pair without a table, or where its meshes touch at that node
    (:mod:`workbench.motion.pair_tables`): its spheres tell then.
    """
    start = tstart[k]
    if start < 0:
        return math.nan
    index = 0
    for i in range(2 * k, 2 * k + 2):
        j = tjoint[i]
        if j < 0:
            break
        n = tcells[i]
        c = math.floor((q[j] - tlower[i]) / tstep[i])
        if tperiodic[i]:
            c %= n
        else:
            c = min(max(c, 0), n - 1)
        index = index * n + c
    return tvalues[start + index]


@helper()
def _clearances(
    q: FloatArray,
    need: FloatArray,
    robot_int: IntArray,
    robot_float: FloatArray,
    sizes: IntArray,
    scene_int: IntArray,
    scene_float: FloatArray,
    tris: FloatArray,
    stop: bool,
    skip: IntArray,
    bounds: FloatArray,
    out: FloatArray,
) -> bool:
    """Clearance bounds (L + P,) [m] into ``out``; False if there is a contact.

    Link–obstacle pairs with ``skip[l, o]`` set are left out (proven free
    elsewhere); ``bounds[l, o]`` receives the bounding sphere's clearance of
    every pair computed.

    Entries whose bound sphere already shows ``need`` or more are not refined;
    entries whose ``need`` is -inf are skipped (set to inf: proven elsewhere).
    With ``stop``, returns at the first contact (later entries unset).
    """
    free = True
    (n_joints, n_links, n_spheres, n_pairs, n_obstacles, n_groups) = (
        sizes[0],
        sizes[1],
        sizes[2],
        sizes[3],
        sizes[4],
        sizes[6],
    )
    jparent = robot_int[0:n_joints]
    jq = robot_int[n_joints : 2 * n_joints]
    ljoint = robot_int[2 * n_joints : 2 * n_joints + n_links]
    base = 2 * n_joints + n_links
    pa = robot_int[base : base + n_pairs]
    pb = robot_int[base + n_pairs : base + 2 * n_pairs]
    lscene = robot_int[base + 2 * n_pairs : base + 2 * n_pairs + n_links]
    base += 2 * n_pairs + n_links
    width = max(1, n_obstacles)
    allowed = robot_int[base : base + n_links * width].reshape(n_links, width)
    base += n_links * width
    lgroup = robot_int[base : base + n_links + 1]
    gfirst = robot_int[base + n_links + 1 : base + n_links + 2 + n_groups]
    base += n_links + 2 + n_groups
    tstart = robot_int[base : base + n_pairs]
    tjoint = robot_int[base + n_pairs : base + 3 * n_pairs]
    tcells = robot_int[base + 3 * n_pairs : base + 5 * n_pairs]
    tperiodic = robot_int[base + 5 * n_pairs : base + 7 * n_pairs]
    f = 0
    jrot = robot_float[f : f + 9 * n_joints].reshape(n_joints, 3, 3)
    f += 9 * n_joints
    jpos = robot_float[f : f + 3 * n_joints].reshape(n_joints, 3)
    f += 3 * n_joints
    jaxis = robot_float[f : f + 3 * n_joints].reshape(n_joints, 3)
    f += 3 * n_joints
    lcenter = robot_float[f : f + 3 * n_links].reshape(n_links, 3)
    f += 3 * n_links
    lradius = robot_float[f : f + n_links]
    f += n_links
    scenter = robot_float[f : f + 3 * n_spheres].reshape(n_spheres, 3)
    f += 3 * n_spheres
    sradius = robot_float[f : f + n_spheres]
    f += n_spheres
    allow = robot_float[f : f + n_links + n_pairs]
    f += n_links + n_pairs
    gcenter = robot_float[f : f + 3 * n_groups].reshape(n_groups, 3)
    f += 3 * n_groups
    gradius = robot_float[f : f + n_groups]
    f += n_groups
    tlower = robot_float[f : f + 2 * n_pairs]
    tstep = robot_float[f + 2 * n_pairs : f + 4 * n_pairs]
    tvalues = robot_float[f + 4 * n_pairs : f + 4 * n_pairs + sizes[7]]
    f += 4 * n_pairs + sizes[7]
    lallow = robot_float[f : f + n_links * width].reshape(n_links, width)
    okind = scene_int[0:n_obstacles]
    ofirst = scene_int[n_obstacles : 2 * n_obstacles + 1]
    orot = scene_float[0 : 9 * n_obstacles].reshape(n_obstacles, 3, 3)
    opos = scene_float[9 * n_obstacles : 12 * n_obstacles].reshape(n_obstacles, 3)
    osize = scene_float[12 * n_obstacles : 15 * n_obstacles].reshape(n_obstacles, 3)
    frame_rot = np.empty((n_joints, 3, 3))
    frame_pos = np.empty((n_joints, 3))
    _frames(q, jparent, jrot, jpos, jaxis, jq, frame_rot, frame_pos)
    bound = np.empty((n_links, 3))
    for li in range(n_links):
        j = ljoint[li]
        _place(frame_rot[j], frame_pos[j], lcenter[li], bound[li])
    world = np.empty((n_spheres, 3))
    gworld = np.empty((n_groups, 3))
    placed = np.zeros(n_links, dtype=np.bool_)
    gplaced = np.zeros(n_groups, dtype=np.bool_)
    for li in range(n_links):
        best = math.inf
        if lscene[li] and need[li] > -math.inf:
            for o in range(n_obstacles):
                if allowed[li, o] or skip[li, o]:
                    continue
                d = _sphere_distance(
                    bound[li],
                    lradius[li],
                    lallow[li, o],
                    o,
                    okind,
                    orot,
                    opos,
                    osize,
                    ofirst,
                    tris,
                    math.inf,
                )
                bounds[li, o] = d
                limit = _limit(need[li], d, lradius[li])
                if d < limit:
                    j = ljoint[li]
                    _place_once(
                        frame_rot[j], frame_pos[j], li, lgroup, placed, gcenter, gworld
                    )
                    d = math.inf
                    for g in range(lgroup[li], lgroup[li + 1]):
                        # A group whose bounding sphere is no nearer than the
                        # nearest sphere so far cannot lower the minimum.
                        dg = _sphere_distance(
                            gworld[g],
                            gradius[g],
                            lallow[li, o],
                            o,
                            okind,
                            orot,
                            opos,
                            osize,
                            ofirst,
                            tris,
                            d,
                        )
                        if dg >= d or dg >= limit:
                            d = min(d, dg)
                            continue
                        _place_once(
                            frame_rot[j],
                            frame_pos[j],
                            g,
                            gfirst,
                            gplaced,
                            scenter,
                            world,
                        )
                        for s in range(gfirst[g], gfirst[g + 1]):
                            ds = _sphere_distance(
                                world[s],
                                sradius[s],
                                lallow[li, o],
                                o,
                                okind,
                                orot,
                                opos,
                                osize,
                                ofirst,
                                tris,
                                d,
                            )
                            d = min(d, ds)
                        if d < 0.0 and stop:
                            out[li] = d
                            return False
                best = min(best, d)
        out[li] = best
        free = free and best >= 0.0
    for k in range(n_pairs):
        if need[n_links + k] == -math.inf:
            out[n_links + k] = math.inf
            continue
        slack = allow[n_links + k]
        table = _table_clearance(
            q, k, tstart, tjoint, tcells, tperiodic, tlower, tstep, tvalues
        )
        if table == table:  # the table's node tells (no sphere is visited)
            out[n_links + k] = table + slack
            if table + slack < 0.0:
                free = False
                if stop:
                    return False
            continue
        a, b = pa[k], pb[k]
        d = _gap(bound[a], bound[b]) - lradius[a] - lradius[b] + slack
        limit = _limit(need[n_links + k], d, lradius[a] + lradius[b])
        if d < limit:
            for li in (a, b):
                j = ljoint[li]
                _place_once(
                    frame_rot[j], frame_pos[j], li, lgroup, placed, gcenter, gworld
                )
            d = math.inf
            for ga in range(lgroup[a], lgroup[a + 1]):
                # A group of a far from b's bounding sphere is far from b.
                coarse = _gap(gworld[ga], bound[b]) - gradius[ga] - lradius[b] + slack
                if coarse >= limit or coarse >= d:
                    d = min(d, coarse)
                    continue
                for gb in range(lgroup[b], lgroup[b + 1]):
                    near = (
                        _gap(gworld[ga], gworld[gb]) - gradius[ga] - gradius[gb] + slack
                    )
                    if near >= d or near >= limit:
                        d = min(d, near)
                        continue
                    _place_once(
                        frame_rot[ljoint[a]],
                        frame_pos[ljoint[a]],
                        ga,
                        gfirst,
                        gplaced,
                        scenter,
                        world,
                    )
                    _place_once(
                        frame_rot[ljoint[b]],
                        frame_pos[ljoint[b]],
                        gb,
                        gfirst,
                        gplaced,
                        scenter,
                        world,
                    )
                    for s in range(gfirst[ga], gfirst[ga + 1]):
                        # A sphere far from the group is far from its spheres.
                        far = (
                            _gap(world[s], gworld[gb])
                            - sradius[s]
                            - gradius[gb]
                            + slack
                        )
                        if far >= d or far >= limit:
                            d = min(d, far)
                            continue
                        for t in range(gfirst[gb], gfirst[gb + 1]):
                            gap = _gap(world[s], world[t]) - sradius[s] - sradius[t]
                            d = min(d, gap + slack)
                    if d < 0.0 and stop:
                        break
                if d < 0.0 and stop:
                    break
            if d < 0.0 and stop:
                out[n_links + k] = d
                return False
        out[n_links + k] = d
        free = free and d >= 0.0
    return free


@helper()
def _motion_free(
    qa: FloatArray,
    qb: FloatArray,
    levers: FloatArray,
    robot_int: IntArray,
    robot_float: FloatArray,
    sizes: IntArray,
    scene_int: IntArray,
    scene_float: FloatArray,
    tris: FloatArray,
    store: FloatArray,
) -> bool:
    """Whether the straight segment qa -> qb is proven free (module docstring).

    The link–obstacle pairs whose bounding-sphere clearance at ``qa`` exceeds
    the link's motion bound over the whole segment are proven free at once
    and left out of every later evaluation.
    """
    n_links, n_pairs = sizes[1], sizes[3]
    n_obstacles = max(1, sizes[4])
    n_entries = n_links + n_pairs
    dq = np.abs(qb - qa)
    motion = levers @ dq  # (L + P,) bound of each entry over the whole segment
    need = motion.copy()
    q = np.empty(len(qa))
    skip = np.zeros((n_links, n_obstacles), dtype=np.int64)
    bounds = np.full((n_links, n_obstacles), -math.inf)
    if not _clearances(
        qa,
        need,
        robot_int,
        robot_float,
        sizes,
        scene_int,
        scene_float,
        tris,
        True,
        skip,
        bounds,
        store[0],
    ):
        return False
    for li in range(n_links):
        for o in range(n_obstacles):
            if bounds[li, o] >= motion[li]:
                skip[li, o] = 1
    if not _clearances(
        qb,
        need,
        robot_int,
        robot_float,
        sizes,
        scene_int,
        scene_float,
        tris,
        True,
        skip,
        bounds,
        store[1],
    ):
        return False
    count = 2
    stack_t = np.empty((64, 2))
    stack_i = np.empty((64, 2), dtype=np.int64)
    stack_t[0, 0], stack_t[0, 1] = 0.0, 1.0
    stack_i[0, 0], stack_i[0, 1] = 0, 1
    top = 1
    while top > 0:
        top -= 1
        t0, t1 = stack_t[top, 0], stack_t[top, 1]
        i0, i1 = stack_i[top, 0], stack_i[top, 1]
        w = t1 - t0
        proven = True
        largest = 0.0
        for k in range(n_entries):
            if store[i0, k] + store[i1, k] < motion[k] * w:
                proven = False
                largest = max(largest, motion[k] * w)
        if proven:
            continue
        if largest < RESOLUTION or count >= len(store) or top + 2 > len(stack_t):
            return False
        tm = 0.5 * (t0 + t1)
        for i in range(len(qa)):
            q[i] = qa[i] + tm * (qb[i] - qa[i])
        for k in range(n_entries):
            if store[i0, k] + store[i1, k] < motion[k] * w:
                need[k] = 0.5 * motion[k] * w
            else:  # proven on the whole interval, so on both halves
                need[k] = -math.inf
        if not _clearances(
            q,
            need,
            robot_int,
            robot_float,
            sizes,
            scene_int,
            scene_float,
            tris,
            True,
            skip,
            bounds,
            store[count],
        ):
            return False
        stack_t[top, 0], stack_t[top, 1] = t0, tm
        stack_i[top, 0], stack_i[top, 1] = i0, count
        stack_t[top + 1, 0], stack_t[top + 1, 1] = tm, t1
        stack_i[top + 1, 0], stack_i[top + 1, 1] = count, i1
        top += 2
        count += 1
    return True


@entry_point(
    outputs=("out",),
    contiguous=_PACKED[1:],
)
def clearances(
    q: FloatArray,
    robot_int: IntArray,
    robot_float: FloatArray,
    sizes: IntArray,
    scene_int: IntArray,
    scene_float: FloatArray,
    tris: FloatArray,
    stop: bool,
    out: FloatArray,
) -> bool:
    """Sphere clearances (L + P,) [m] at q; False on contact.

    Every entry refined; with ``stop``, only entries whose bounding sphere
    touches, returning at the first contact (later entries unset).
    """
    need = np.full(len(out), 0.0 if stop else np.inf)
    n_obstacles = max(1, sizes[4])
    skip = np.zeros((sizes[1], n_obstacles), dtype=np.int64)
    bounds = np.empty((sizes[1], n_obstacles))
    return _clearances(
        q,
        need,
        robot_int,
        robot_float,
        sizes,
        scene_int,
        scene_float,
        tris,
        stop,
        skip,
        bounds,
        out,
    )


@entry_point(
    outputs=("store",),
    contiguous=_PACKED,
)
def motion_free(
    qa: FloatArray,
    qb: FloatArray,
    levers: FloatArray,
    robot_int: IntArray,
    robot_float: FloatArray,
    sizes: IntArray,
    scene_int: IntArray,
    scene_float: FloatArray,
    tris: FloatArray,
    store: FloatArray,
) -> bool:
    """Whether the segment qa -> qb is proven free, both ends included."""
    return _motion_free(
        qa,
        qb,
        levers,
        robot_int,
        robot_float,
        sizes,
        scene_int,
        scene_float,
        tris,
        store,
    )


@helper(forceinline=True)
def _nearest(nodes: FloatArray, count: int, q: FloatArray) -> int:
    best, index = math.inf, 0
    for i in range(count):
        d = 0.0
        for k in range(len(q)):
            e = nodes[i, k] - q[k]
            d += e * e
        if d < best:
            best, index = d, i
    return index


@helper(forceinline=True)
def _steer(
    q_from: FloatArray, target: FloatArray, step: float, out: FloatArray
) -> bool:
    """Set out (nq,) to the point at most ``step`` [rad] from q_from to target.

    Returns whether that point is the target itself.
    """
    delta = target - q_from
    length = math.sqrt(delta @ delta)
    reached = length <= step
    scale = 1.0 if reached else step / length
    for i in range(len(out)):
        out[i] = q_from[i] + scale * delta[i]
    return reached


@entry_point(
    outputs=("nodes", "parents", "counts", "state", "store"),
    contiguous=_PACKED,
)
def grow_trees(
    nodes: FloatArray,
    parents: IntArray,
    counts: IntArray,
    state: IntArray,
    uniforms: FloatArray,
    lower: FloatArray,
    upper: FloatArray,
    step: float,
    levers: FloatArray,
    robot_int: IntArray,
    robot_float: FloatArray,
    sizes: IntArray,
    scene_int: IntArray,
    scene_float: FloatArray,
    tris: FloatArray,
    store: FloatArray,
) -> None:
    """RRT-Connect iterations, one per row of ``uniforms`` (R, nq) in [0, 1).

    Args:
        nodes: (2, N, nq) configurations of the two trees (0: start, 1: goal).
        parents: (2, N) parent index, -1 for a root.
        counts: (2,) nodes in each tree.
        state: (4,) in/out: [connected (0/1), node of tree 0, node of tree 1,
            iterations done]; the trees alternate by iteration parity.
        uniforms: (R, nq) random numbers in [0, 1), one sample per row.
        lower: (nq,) lower joint limits [rad].
        upper: (nq,) upper joint limits [rad].
        step: Longest extension [rad], Euclidean in joint space.
        levers: (L + P, nq) lever arms [m/rad] of the clearance entries.
        robot_int: Packed robot integers (``PackedArrays``).
        robot_float: Packed robot floats.
        sizes: Counts: joints, links, spheres, pairs, obstacles, nv.
        scene_int: Packed obstacle kinds and triangle offsets.
        scene_float: Packed obstacle poses and sizes.
        tris: (T, 3, 3) mesh triangles [m], obstacle frames.
        store: (E, L + P) scratch rows for the clearances of one segment.
    """
    n = nodes.shape[2]
    capacity = nodes.shape[1]
    q_new, q = np.empty(n), np.empty(n)
    for row in range(len(uniforms)):
        if state[0] == 1:
            return
        a = state[3] % 2
        b = 1 - a
        state[3] += 1
        if counts[0] + 1 >= capacity or counts[1] + 1 >= capacity:
            return
        target = lower + uniforms[row] * (upper - lower)
        near = _nearest(nodes[a], counts[a], target)
        _steer(nodes[a, near], target, step, q_new)
        if not _motion_free(
            nodes[a, near],
            q_new,
            levers,
            robot_int,
            robot_float,
            sizes,
            scene_int,
            scene_float,
            tris,
            store,
        ):
            continue
        new = counts[a]
        nodes[a, new] = q_new
        parents[a, new] = near
        counts[a] += 1
        # Connect tree b to q_new.
        tip = _nearest(nodes[b], counts[b], q_new)
        while counts[b] + 1 < capacity:
            reached = _steer(nodes[b, tip], q_new, step, q)
            if not _motion_free(
                nodes[b, tip],
                q,
                levers,
                robot_int,
                robot_float,
                sizes,
                scene_int,
                scene_float,
                tris,
                store,
            ):
                break
            k = counts[b]
            nodes[b, k] = q
            parents[b, k] = tip
            counts[b] += 1
            tip = k
            if reached:
                state[0] = 1
                state[1 + a] = new
                state[1 + b] = tip
                return


@entry_point(
    outputs=("path", "length", "store"),
    contiguous=_PACKED,
)
def shortcut(
    path: FloatArray,
    length: IntArray,
    uniforms: FloatArray,
    levers: FloatArray,
    robot_int: IntArray,
    robot_float: FloatArray,
    sizes: IntArray,
    scene_int: IntArray,
    scene_float: FloatArray,
    tris: FloatArray,
    store: FloatArray,
) -> None:
    """Shorten a free polyline in place: greedy reduction, then random shortcuts.

    Args:
        path: (M, nq) buffer whose first ``length[0]`` rows are the path.
        length: (1,) in/out number of waypoints.
        uniforms: (R, 2) in [0, 1): one random shortcut per row, between two
            points on two segments (OMPL's ``shortcutPath``).
        levers: (L + P, nq) lever arms [m/rad] of the clearance entries.
        robot_int: Packed robot integers (``PackedArrays``).
        robot_float: Packed robot floats.
        sizes: Counts: joints, links, spheres, pairs, obstacles, nv.
        scene_int: Packed obstacle kinds and triangle offsets.
        scene_float: Packed obstacle poses and sizes.
        tris: (T, 3, 3) mesh triangles [m], obstacle frames.
        store: (E, L + P) scratch rows for the clearances of one segment.
    """
    n = path.shape[1]
    # Greedy: from each kept waypoint jump to the farthest one it sees.
    k = length[0]
    out = 0
    i = 0
    while i < k - 1:
        j = k - 1
        while j > i + 1:
            if _motion_free(
                path[i],
                path[j],
                levers,
                robot_int,
                robot_float,
                sizes,
                scene_int,
                scene_float,
                tris,
                store,
            ):
                break
            j -= 1
        path[out] = path[i]
        out += 1
        i = j
    path[out] = path[k - 1]
    length[0] = out + 1
    qa, qb = np.empty(n), np.empty(n)
    for row in range(len(uniforms)):
        k = length[0]
        if k < 3:
            return
        x = uniforms[row, 0] * (k - 1)
        y = uniforms[row, 1] * (k - 1)
        if x > y:
            x, y = y, x
        sa, sb = int(x), int(y)
        if sa == k - 1:
            sa = k - 2
        if sb == k - 1:
            sb = k - 2
        if sb <= sa:
            continue
        ta, tb = x - sa, y - sb
        qa[:] = path[sa] + ta * (path[sa + 1] - path[sa])
        qb[:] = path[sb] + tb * (path[sb + 1] - path[sb])
        old = 0.0
        e = qa - path[sa + 1]
        old += math.sqrt(e @ e)
        for m in range(sa + 1, sb):
            e = path[m + 1] - path[m]
            old += math.sqrt(e @ e)
        e = qb - path[sb]
        old += math.sqrt(e @ e)
        e = qb - qa
        if math.sqrt(e @ e) >= old - 1e-9:
            continue
        if not _motion_free(
            qa,
            qb,
            levers,
            robot_int,
            robot_float,
            sizes,
            scene_int,
            scene_float,
            tris,
            store,
        ):
            continue
        # path[..sa], qa, qb, path[sb+1..]
        tail = k - (sb + 1)
        new_length = sa + 1 + 2 + tail
        if new_length > len(path):
            continue
        if sa + 3 <= sb + 1:
            for m in range(tail):
                path[sa + 3 + m] = path[sb + 1 + m]
        else:
            for m in range(tail - 1, -1, -1):
                path[sa + 3 + m] = path[sb + 1 + m]
        path[sa + 1] = qa
        path[sa + 2] = qb
        length[0] = new_length
