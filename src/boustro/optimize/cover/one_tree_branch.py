"""Branching on the 1-tree (:mod:`~boustro.optimize.cover.one_tree`): a higher lower bound on
the moves of one layout (or box) where Held-Karp's relaxation is a few metres short
(docs/mission_time.md, "Branching on the 1-tree").

**What is bounded.** :mod:`~.one_tree` reduces every plan of a layout's sandwich to a
Hamiltonian cycle ``C`` over the counted lanes' ends and a dummy node, holding every lane as an
edge, whose cost under the distances ``dist`` (between the ends' ranges) is at most the plan's
moves plus its extra lanes (and, at the collapsed outermost ends, the lanes' length outside the
inner pieces). In ``C`` every end has degree 2: its lane and exactly one *non-lane* edge (to
another end, or to the dummy). This holds whatever points of their ranges the plan's ends are
at: the ends are nodes (a lane's start and end, whichever way it is flown), the ranges only
set the costs ``dist[a, b]`` (each at most the plan's move between the two points), so the
degree structure is that of ``C`` for every plan of a box as at a single layout.

**Branching.** Where the best 1-tree has an end ``e`` with ``k >= 2`` non-lane edges ``x_1 ..
x_k`` (degree 3 or more), every cycle ``C`` has exactly one non-lane edge at ``e`` and it is
either some ``x_j`` or none of them. The children "``x_j`` is ``e``'s non-lane edge" (``x_j``
forced, every other non-lane edge at ``e`` and at ``x_j``'s other end forbidden: the other end
has one non-lane edge too) for each ``j`` and "none of them" (``x_1 .. x_k`` forbidden at
``e``) split the cycles into disjoint sets that cover them all. In a child, every cycle of its
set is still a 1-tree avoiding the forbidden edges and holding the forced ones, so Held-Karp's
``L(pi) = min over those 1-trees of (c_ij + pi_i + pi_j) - 2 sum(pi)`` is at most each of its
cycles' costs for every ``pi``; a child with no such cycle (an end with no allowed non-lane edge,
forced non-lane edges closing a cycle of lanes without the dummy, more than two forced dummy
edges, no spanning tree of allowed edges, fewer than two allowed dummy edges) has none: its bound
is ``+inf``. A child's cycles are its parent's, so it also keeps its parent's bound (``max``).
The minimum over the leaves of the branching (which partition the cycles) is at most every
cycle's cost: a lower bound on the plan's moves, at least the root's (the 1-tree of
:mod:`~.one_tree`). Any multipliers give a valid child bound, so warm starts from the parent's
and any number of steps are sound.

**The constrained 1-tree.** Prim over the lanes contracted (as :func:`~.one_tree._one_tree`):
a lane reached from the tree by a forced edge is added before any other (Prim on the graph
with the forced edges' components contracted, which are a forest: checked), a forbidden edge
costs ``inf`` (no finite key left while lanes remain: no spanning tree, ``+inf``); the dummy
takes its forced ends, then the cheapest allowed ones.
"""

from __future__ import annotations

import math

import numpy as np

from ..._jit import jit_globals

__all__ = ["BRANCH_NODES", "BRANCH_STEPS", "swap"]

#: Held-Karp problems solved per branched layout (the root excluded). Any number gives a valid
#: bound (the leaves of any branching partition the cycles). 12 in the seventeenth round; 48
#: in the eighteenth: the benchmark's random areas 12, 13, 23, 28, 32 and 97 (of 100) certified
#: by the last pass, whose lowest boxes 12 children left 0.03-1.3 s below the discard value
#: (docs/mission_time.md, "Where the last 35 certificates are lost").
BRANCH_NODES = 48
#: Subgradient steps per child (warm-started from its parent's best multipliers).
BRANCH_STEPS = 40
#: The dummy as an end's non-lane partner (in ``fp``, the forced partner of each end).
DUMMY = -2


def _tree_fb(cd, pi, n, deg, key, near, done, kf, fp, dstate, tu, tv):
    """The 1-tree's cost under ``pi`` minus ``2 sum(pi)`` over the allowed edges (``cd``: the
    distances, ``inf`` where forbidden), holding the forced ones (``fp[e]``: end ``e``'s forced
    partner, :data:`DUMMY`, or -1) and the dummy's forced ends (``dstate`` 2; 1 forbidden);
    ``inf`` where no such 1-tree exists. Its ends' degrees in ``deg``, its tree edges in ``tu,
    tv`` (``n - 1``) and the dummy's two ends in ``tu[n - 1], tv[n - 1]``."""
    m = 2 * n
    for e in range(m):
        deg[e] = 1
    total = 0.0
    for a in range(n):
        key[a] = math.inf
        done[a] = False
        kf[a] = False
    key[0] = 0.0
    near[0] = -1
    a, best, used = 0, 0.0, 0
    for it in range(n):
        done[a] = True
        if near[a] >= 0:
            total += best
            u, w = near[a] // 4, 2 * a + near[a] % 2
            deg[u] += 1
            deg[w] += 1
            tu[used], tv[used] = u, w
            used += 1
        nxt, low, nforced = -1, math.inf, False
        for b in range(n):
            if done[b]:
                continue
            kb, nb, fb = key[b], near[b], kf[b]
            if not fb:
                for side in range(2):
                    r = 2 * a + side
                    for bs in range(2):
                        if fb:
                            break
                        c = cd[r, 2 * b + bs] + pi[r] + pi[2 * b + bs]
                        if fp[r] == 2 * b + bs:
                            kb, nb, fb = c, r * 4 + bs, True
                        elif c < kb:
                            kb, nb = c, r * 4 + bs
                key[b], near[b], kf[b] = kb, nb, fb
            if fb:
                if not nforced:
                    nxt, low, nforced = b, kb, True
            elif not nforced and kb < low:
                nxt, low = b, kb
        if it < n - 1 and (nxt < 0 or low == math.inf):
            return math.inf  # no spanning tree of allowed edges
        a, best = nxt, low
    i1, i2 = -1, -1
    for e in range(m):  # the dummy: its forced ends, then its cheapest allowed ones
        if dstate[e] == 2:
            if i1 < 0:
                i1 = e
            else:
                i2 = e
    for e in range(m):
        if dstate[e] != 0:
            continue
        if i1 < 0 or (dstate[i1] == 0 and pi[e] < pi[i1]):
            i1, i2 = e, i1
        elif i2 < 0 or (dstate[i2] == 0 and pi[e] < pi[i2]):
            i2 = e
    if i1 < 0 or (i2 < 0 and m > 1):
        return math.inf
    total += pi[i1] + (pi[i2] if i2 >= 0 else 0.0)
    deg[i1] += 1
    tu[n - 1], tv[n - 1] = i1, i2
    if i2 >= 0:
        deg[i2] += 1
    for e in range(m):
        total -= pi[e]
    return total


def _apply(dist, n, node, parent, op0, op1, ops, cd, fp, dstate, root):
    """The constraints of ``node`` (its ops and its ancestors'): ``cd`` (``dist`` with the
    forbidden non-lane edges ``inf``), ``fp`` and ``dstate``; ``False`` where they admit no
    cycle (module docstring)."""
    m = 2 * n
    for a in range(m):
        fp[a] = -1
        dstate[a] = 0
        for b in range(m):
            cd[a, b] = dist[a, b]
    cur = node
    while cur != root:
        for o in range(op0[cur], op1[cur]):
            kind, e, x = ops[o, 0], ops[o, 1], ops[o, 2]
            if kind == 1:  # forbid the edge e-x (x the dummy: DUMMY)
                if x == DUMMY:
                    if dstate[e] == 2:
                        return False
                    dstate[e] = 1
                else:
                    if fp[e] == x:
                        return False
                    cd[e, x] = cd[x, e] = math.inf
            else:  # force e-x: every other non-lane edge at e (and at x) forbidden
                if (fp[e] >= 0 and fp[e] != x) or (fp[e] == DUMMY and x != DUMMY):
                    return False
                fp[e] = x
                if x == DUMMY:
                    if dstate[e] == 1:
                        return False
                    dstate[e] = 2
                else:
                    if (fp[x] != -1 and fp[x] != e) or cd[e, x] == math.inf:
                        return False
                    fp[x] = e
        cur = parent[cur]
    for e in range(m):  # the forced edges' consequences: one non-lane edge an end
        if fp[e] == -1:
            continue
        for b in range(m):
            if b != e and b != (e ^ 1) and b != fp[e]:
                cd[e, b] = cd[b, e] = math.inf
        if fp[e] != DUMMY:
            if dstate[e] == 2:
                return False
            dstate[e] = 1
    n_dummy = 0
    for e in range(m):
        if dstate[e] == 2:
            n_dummy += 1
        allowed = dstate[e] != 1
        if not allowed:
            for b in range(m):
                if b != e and b != (e ^ 1) and cd[e, b] < math.inf:
                    allowed = True
                    break
        if not allowed:
            return False
    if n_dummy > 2:
        return False
    # the forced edges between lanes: a forest (a cycle of lanes without the dummy: no tour)
    comp = np.empty(n, dtype=np.int64)
    for i in range(n):
        comp[i] = i
    for e in range(m):
        x = fp[e]
        if x < 0 or x < e:
            continue
        ra, rb = e // 2, x // 2
        while comp[ra] != ra:
            ra = comp[ra]
        while comp[rb] != rb:
            rb = comp[rb]
        if ra == rb:
            return False
        comp[ra] = rb
    return True


def _ascent(cd, pi, best_pi, n, deg, key, near, done, kf, fp, dstate, tu, tv, steps, enough,
            s, lam):  # fmt: skip
    """Held-Karp's subgradient steps from ``pi`` over the constrained 1-trees: the best value
    (``-inf`` if none finite, ``inf`` where the constraints admit no 1-tree), its multipliers in
    ``best_pi``; stops once it reaches ``enough``."""
    best = -math.inf
    stall = 0
    for e in range(2 * n):
        best_pi[e] = pi[e]
    for _ in range(steps):
        val = _tree_fb(cd, pi, n, deg, key, near, done, kf, fp, dstate, tu, tv)
        if val == math.inf:
            return math.inf
        if val > best + 1e-9 * abs(best) or best == -math.inf:
            best, stall = val, 0
            for e in range(2 * n):
                best_pi[e] = pi[e]
            if best >= enough:
                break
        else:
            stall += 1
            if stall >= 3:
                lam *= 0.5
                stall = 0
        norm = 0.0
        for e in range(2 * n):
            norm += (deg[e] - 2) * (deg[e] - 2)
        if norm == 0.0:
            break
        step = lam * 0.2 * max(abs(best), s) / norm
        for e in range(2 * n):
            pi[e] += step * (deg[e] - 2)
    return best


def _branch(dist, n, root_pi, root_val, enough, s, nodes, steps):
    """The least bound over the leaves of a best-first branching (module docstring) from the
    root 1-tree (multipliers ``root_pi``, value ``root_val``), at most ``nodes`` children
    solved, stopping once every leaf's bound reaches ``enough``: at least ``root_val``."""
    m = 2 * n
    cap = nodes + 2
    pis = np.empty((cap, m))
    bound = np.full(cap, math.inf)
    parent = np.full(cap, -1, dtype=np.int64)
    op0 = np.zeros(cap, dtype=np.int64)
    op1 = np.zeros(cap, dtype=np.int64)
    leaf = np.zeros(cap, dtype=np.bool_)
    ops = np.empty((cap * (m + 1), 3), dtype=np.int64)
    n_ops = 0
    cd = np.empty((m, m))
    fp = np.empty(m, dtype=np.int64)
    dstate = np.empty(m, dtype=np.int64)
    pi, best_pi = np.empty(m), np.empty(m)
    deg = np.empty(m, dtype=np.int64)
    key, near = np.empty(n), np.empty(n, dtype=np.int64)
    done, kf = np.empty(n, dtype=np.bool_), np.empty(n, dtype=np.bool_)
    tu, tv = np.empty(n, dtype=np.int64), np.empty(n, dtype=np.int64)
    for e in range(m):
        pis[0, e] = root_pi[e]
    bound[0], leaf[0] = root_val, True
    count = 1
    while True:
        low, pick = math.inf, -1  # the open leaf of the least bound
        for i in range(count):
            if leaf[i] and bound[i] < low:
                low, pick = bound[i], i
        if pick < 0 or low >= enough:
            break
        if not _apply(dist, n, pick, parent, op0, op1, ops, cd, fp, dstate, -1):
            bound[pick] = math.inf  # cannot happen at a solved node; kept for safety
            continue
        for e in range(m):
            pi[e] = pis[pick, e]
        val = _tree_fb(cd, pi, n, deg, key, near, done, kf, fp, dstate, tu, tv)
        if val == math.inf:
            bound[pick] = math.inf
            continue
        e_br, k_br = -1, 0  # the end of the most non-lane edges in the leaf's 1-tree
        for e in range(m):
            if deg[e] - 1 > k_br and deg[e] >= 3:
                e_br, k_br = e, deg[e] - 1
        if e_br < 0 or count + k_br + 1 > cap:
            break  # a tour (the bound is its cost) or the budget: the leaves stand
        xs = np.empty(k_br, dtype=np.int64)
        j = 0
        for t in range(n - 1):
            if tu[t] == e_br:
                xs[j] = tv[t]
                j += 1
            elif tv[t] == e_br:
                xs[j] = tu[t]
                j += 1
        if tu[n - 1] == e_br or tv[n - 1] == e_br:
            xs[j] = DUMMY
            j += 1
        leaf[pick] = False
        for c in range(k_br + 1):
            child = count
            count += 1
            parent[child], op0[child] = pick, n_ops
            if c < k_br:  # x_c is e's non-lane edge
                ops[n_ops, 0], ops[n_ops, 1], ops[n_ops, 2] = 2, e_br, xs[c]
                n_ops += 1
            else:  # none of them
                for t in range(k_br):
                    ops[n_ops, 0], ops[n_ops, 1], ops[n_ops, 2] = 1, e_br, xs[t]
                    n_ops += 1
            op1[child] = n_ops
            leaf[child] = True
            if not _apply(dist, n, child, parent, op0, op1, ops, cd, fp, dstate, -1):
                continue  # no cycle: bound inf
            for e in range(m):
                pi[e] = pis[pick, e]
            val = _ascent(cd, pi, best_pi, n, deg, key, near, done, kf, fp, dstate, tu, tv,
                          steps, enough, s, 0.25)  # fmt: skip
            bound[child] = max(val, bound[pick])
            for e in range(m):
                pis[child, e] = best_pi[e]
    low = math.inf
    for i in range(count):
        if leaf[i] and bound[i] < low:
            low = bound[i]
    return max(low, root_val)


def swap() -> None:
    """The helpers compiled where :func:`_branch` looks them up (before a kernel that calls it
    is compiled: :func:`~boustro._jit.compiled`'s ``before``)."""
    jit_globals(globals(), ("_tree_fb", "_apply", "_ascent"))
