"""A kincal.markers_t's target, as the overlays draw it: the identified markers' outline
(their convex hull) and the target's id. Shared by `kincal view` and the MCAP export."""


def convex_hull(points):
    """Andrew's monotone chain; counter-clockwise, no repeated end point."""
    pts = sorted(set(points))
    if len(pts) < 3:
        return pts

    def cross(o, a, b):
        return (a[0] - o[0]) * (b[1] - o[1]) - (a[1] - o[1]) * (b[0] - o[0])

    lower, upper = [], []
    for p in pts:
        while len(lower) >= 2 and cross(lower[-2], lower[-1], p) <= 0:
            lower.pop()
        lower.append(p)
    for p in reversed(pts):
        while len(upper) >= 2 and cross(upper[-2], upper[-1], p) <= 0:
            upper.pop()
        upper.append(p)
    return lower[:-1] + upper[:-1]


def target_outline(m):
    """(outline, target id) of a markers_t: the hull of its identified markers in camera
    pixels ([] when fewer than three) and the id of their target (-1 when none is)."""
    ident = [(m.u[i], m.v[i]) for i in range(m.num_markers) if m.id[i] >= 0]
    target = next((m.target_id[i] for i in range(m.num_markers) if m.id[i] >= 0), -1)
    hull = convex_hull(ident)
    return (hull if len(hull) >= 3 else []), target
