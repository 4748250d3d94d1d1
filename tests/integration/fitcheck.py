"""fitcheck.py -- independent statistics of a 2D specimen, recomputed from its geometry
(python3 standard library only), for test_fit.py.

Nothing here reads a number the daemon reports about itself: areas come from the returned
polygons (shoelace), orientations from the polygons' convex hulls (a brute-force minimum
width over the hull edges, not rotating calipers), and the laws' CDFs are written out here from
their definitions (api.md "2D size laws", core/2d/gp_law.h):
  - lognormal of mean m and coefficient of variation c: sigma^2 = ln(1 + c^2),
    mu = ln m - sigma^2 / 2, F(x) = (1 + erf((ln x - mu) / (sigma sqrt 2))) / 2;
  - the cosine orientation law of mean t and anisotropy a, density proportional to
    (1 + a)/2 + (1 - a)/2 cos(2 (theta - t)), its CDF on the window [t - 90, t + 90).
"""
import math
from fractions import Fraction


# ---------------------------------------------------------------------------------- geometry

def shoelace(ring):
    """Signed area of a closed ring [[x, y], ...] (counter-clockwise positive)."""
    n = len(ring)
    return 0.5 * math.fsum(ring[i][0] * ring[(i + 1) % n][1] - ring[(i + 1) % n][0] * ring[i][1]
                           for i in range(n))


def container_area(container):
    """Area of a {"polygon", "holes"} container (either ring orientation)."""
    a = abs(shoelace(container["polygon"]))
    return a - math.fsum(abs(shoelace(h)) for h in container.get("holes", []))


def _orient(o, a, b):
    """Sign of cross(a - o, b - o), exact (a float filter, then rational arithmetic)."""
    t1 = (a[0] - o[0]) * (b[1] - o[1])
    t2 = (a[1] - o[1]) * (b[0] - o[0])
    d = t1 - t2
    if abs(d) > 1e-12 * (abs(t1) + abs(t2)):
        return 1 if d > 0 else -1
    fo = (Fraction(o[0]), Fraction(o[1]))
    e = ((Fraction(a[0]) - fo[0]) * (Fraction(b[1]) - fo[1])
         - (Fraction(a[1]) - fo[1]) * (Fraction(b[0]) - fo[0]))
    return (e > 0) - (e < 0)


def convex_hull(points):
    """Andrew's monotone chain, counter-clockwise, collinear points dropped."""
    pts = sorted(set((float(p[0]), float(p[1])) for p in points))
    if len(pts) < 3:
        return pts
    lower, upper = [], []
    for p in pts:
        while len(lower) >= 2 and _orient(lower[-2], lower[-1], p) <= 0:
            lower.pop()
        lower.append(p)
    for p in reversed(pts):
        while len(upper) >= 2 and _orient(upper[-2], upper[-1], p) <= 0:
            upper.pop()
        upper.append(p)
    return lower[:-1] + upper[:-1]


def _wrap_half_pi(ang):
    """An angle (radians) of a pi-periodic direction into (-pi/2, pi/2]."""
    if ang <= -math.pi / 2:
        ang += math.pi
    elif ang > math.pi / 2:
        ang -= math.pi
    return ang


TIE_REL = 1e-9


def min_caliper_deg(ring):
    """Direction (degrees, (-90, 90]) of the convex-hull edge across which the hull's width is
    smallest (gp_geom.h gp_min_caliper, Mollon & Zhao Fig. 1a), by brute force: every hull edge,
    its width = the largest distance of a hull vertex from the edge's line.
    Returns (angle_deg, ambiguous): ambiguous when another edge of a different direction has a
    width within TIE_REL (relative) of the smallest, so that rounding may pick either."""
    h = convex_hull(ring)
    m = len(h)
    if m < 3:
        raise ValueError("degenerate polygon: %r" % (ring,))
    edges = []
    for i in range(m):
        a, b = h[i], h[(i + 1) % m]
        ex, ey = b[0] - a[0], b[1] - a[1]
        ln = math.hypot(ex, ey)
        w = max((ex * (q[1] - a[1]) - ey * (q[0] - a[0])) / ln for q in h)
        edges.append((w, _wrap_half_pi(math.atan2(ey, ex))))
    wmin, ang = min(edges, key=lambda e: e[0])
    ambiguous = False
    for w, a2 in edges:
        if w <= wmin * (1 + TIE_REL):
            d = abs(a2 - ang) % math.pi
            if min(d, math.pi - d) > 1e-9:
                ambiguous = True
    return ang * (180.0 / math.pi), ambiguous


def point_in_ring(p, ring):
    x, y = p
    inside = False
    n = len(ring)
    for i in range(n):
        x1, y1 = ring[i]
        x2, y2 = ring[(i + 1) % n]
        if (y1 > y) != (y2 > y):
            xc = x1 + (y - y1) * (x2 - x1) / (y2 - y1)
            if xc > x:
                inside = not inside
    return inside


def _seg_dist(p, a, b):
    ax, ay = b[0] - a[0], b[1] - a[1]
    l2 = ax * ax + ay * ay
    t = 0.0 if l2 == 0 else max(0.0, min(1.0, ((p[0] - a[0]) * ax + (p[1] - a[1]) * ay) / l2))
    return math.hypot(p[0] - a[0] - t * ax, p[1] - a[1] - t * ay)


def seed_part(cell):
    """The polygon of a cell that holds its seed (the nearest one for a seed on a boundary)."""
    polys = cell["polygons"]
    if len(polys) == 1:
        return polys[0]
    s = cell["seed"]
    best, bd = None, float("inf")
    for r in polys:
        if point_in_ring(s, r):
            d = 0.0
        else:
            d = min(_seg_dist(s, r[i], r[(i + 1) % len(r)]) for i in range(len(r)))
        if d < bd:
            best, bd = r, d
    return best


def angle_diff_deg(a, b):
    """Distance between two pi-periodic directions, degrees in [0, 90]."""
    d = abs(a - b) % 180.0
    return min(d, 180.0 - d)


# ---------------------------------------------------------------------------------- laws

def lognormal_cdf(mean, cov):
    s2 = math.log1p(cov * cov)
    mu = math.log(mean) - s2 / 2
    s = math.sqrt(s2)

    def F(x):
        if x <= 0:
            return 0.0
        return 0.5 * (1.0 + math.erf((math.log(x) - mu) / (s * math.sqrt(2.0))))
    return F


def orient_wrap(mean_deg, theta):
    lo = mean_deg - 90.0
    t = math.fmod(theta - lo, 180.0)
    if t < 0:
        t += 180.0
    if t >= 180.0:
        t = 0.0
    return lo + t


def cosine_cdf(mean_deg, a):
    """CDF of the cosine law on the window [mean - 90, mean + 90): with x = theta - mean + 90
    (radians, in [0, pi)) the density is (1+a)/2 - (1-a)/2 cos 2x, whose integral is
    (1+a)/2 x - (1-a)/4 sin 2x, normalised by its value (1+a) pi/2 at x = pi."""
    def F(theta):
        x = math.radians(orient_wrap(mean_deg, theta) - mean_deg + 90.0)
        return ((1 + a) / 2 * x - (1 - a) / 4 * math.sin(2 * x)) / ((1 + a) * math.pi / 2)
    return F


def ks(values, cdf):
    """Kolmogorov-Smirnov distance of a sample to a CDF (exact, ties included). The values are
    ordered by their CDF, not by themselves: a direction is ordered on its law's window (90 deg
    is the window's start -90 when the mean is 0)."""
    u = sorted(cdf(v) for v in values)
    n = len(u)
    d = 0.0
    for i, f in enumerate(u):
        d = max(d, (i + 1) / n - f, f - i / n)
    return d


def mean_cov(values):
    n = len(values)
    m = math.fsum(values) / n
    if n < 2:
        return m, 0.0
    var = math.fsum((v - m) ** 2 for v in values) / (n - 1)
    return m, math.sqrt(var) / m


def ks_critical(n):
    return 1.36 / math.sqrt(n)


def equivalent_diameter(area):
    return math.sqrt(4.0 * area / math.pi)


def passing_by_mass(areas, diameters):
    """Percent passing by mass (mass proportional to area in 2D): a grain passes a sieve of
    diameter D when its equivalent diameter is below D."""
    total = math.fsum(areas)
    out = []
    for D in diameters:
        out.append(100.0 * math.fsum(a for a in areas if equivalent_diameter(a) < D) / total)
    return out


def sieve_number_mean_area(rows, unit):
    """Number mean of the grain area under a sieve law (api.md: mass uniform in d between
    sieves; number density in d is the mass density / d^2 since mass is proportional to d^2):
    mean A = (pi/4) sum s_k dd_k / sum s_k (1/d_{k-1} - 1/d_k), s_k the mass per unit d."""
    num = den = 0.0
    for (d0, p0), (d1, p1) in zip(rows, rows[1:]):
        d0, d1 = d0 * unit, d1 * unit
        s = (p1 - p0) / (d1 - d0)
        num += s * (d1 - d0)
        den += s * (1.0 / d0 - 1.0 / d1)
    return math.pi / 4 * num / den
