"""Two quasi-static growth runs that must break the same bonds in the same steps (the direct
path against another solver path: tests/verification/fracture_krylov.sh, mpi_fracture_coupled.sh).

same(ref, other, nodes=True): damage.csv's counts equal row by row, the reactions and the load
point's displacement within 1e-8 of the largest (each path's solves stop at a relative residual
of 1e-12 or 1e-10; a crack that took another path would differ by O(1)), and, with nodes, every
node's final damage in pd_nodes.csv equal to the bit."""
import csv


def rows(d):
    return list(csv.DictReader(open(d + "/damage.csv")))


def damage(d):
    return [r["damage"] for r in csv.DictReader(open(d + "/pd_nodes.csv"))]


def same(ref, other, nodes=True):
    a, b = rows(ref), rows(other)
    assert len(a) == len(b) and len(a) > 0, (other, len(a), len(b))
    cols = [c for c in a[0] if c.startswith("reaction_") or c.startswith("load_u")]
    peak = max(abs(float(r[c])) for r in a for c in cols)
    for r, s in zip(a, b):
        for c in ("iterations", "broken_bonds", "damaged_nodes", "nodes_broken", "released_nodes"):
            assert r[c] == s[c], (other, r["step"], c, r[c], s[c])
        for c in cols:
            assert abs(float(r[c]) - float(s[c])) <= 1e-8 * peak, (other, r["step"], c, r[c], s[c])
    if nodes:
        assert damage(other) == damage(ref), other
