/* gp_transfer.h -- did the flip tiling keep the sample's structure? (Dang & Meguid 2010,
 * "Results and Discussion": Table 3's porosity, coordination number and fabric (Eq. 14),
 * Table 2's grain-size distribution, and the radial distribution function the paper's
 * introduction names as the mark of a realistic structure (Jullien et al. 1996), all measured
 * on the geometry of the sample S0 and of the final packing, then compared figure by figure.)
 *
 * gp_transfer_measure(packing, params) -> gp_transfer_side: the figures of one packing.
 * gp_transfer_compare(a, b) -> gp_transfer_diff: the largest difference of each figure.
 * Run it on S0 and on its tiling; the spec's stats.transfer is the two sides and the diff.
 *
 * The figures of one packing (n spheres xyzr in the box [0, box]):
 *   - porosity 1 - solid / box volume, solid = each sphere clipped by the box's planes
 *     (gp_dem3d_solid_volume; sphere-sphere overlaps counted twice, as gp_specimen3d does).
 *     For a flip tiling (packing.tiles) each copy is clipped to its own tile instead, as
 *     gp_specimen3d measures a tiling: a sphere's cap beyond an inner face lies inside its
 *     mirror image, and counting it would count that volume twice. So a tiling's porosity
 *     is its sample's, to rounding (1e-16 here).
 *   - coordination number (2 C + W) / n with the W wall contacts counted (a wall contact
 *     becomes half of a pair with the sphere's image when flipped: the number is
 *     flip-invariant, exactly, as integers), and 2 C / n with sphere-sphere contacts only
 *     (this one grows in a tiling: the inner faces' wall contacts become pairs).
 *   - fabric, Eq. 14, weighted as gp_dem3d_fabric (a pair counted by both spheres, a wall
 *     contact by one). Its diagonal is flip-invariant. An off-diagonal F_ab is not: the
 *     copies mirrored along a (odd tile index) have n_a negated, so a tiling's F_ab is the
 *     sample's times m_a m_b, m = 0 for an even number of tiles along the axis and 1 / n for
 *     an odd n (Table 3's off-diagonals fall from 1e-3 in phase 1 to 1e-5 in phase 2).
 *   - PSD: percent passing (diameter 2 r < sieve) by number and by weight (d^3) at the given
 *     sieves, and d50 by weight (the smallest diameter D with weight(d <= D) >= half). The
 *     weights are summed as integers (each d^3 / d_max^3 rounded to a multiple of 2^-62):
 *     the sums do not depend on the order, so a tiling's d50 and PSD by number are its
 *     sample's, bit for bit, and its PSD by weight too when the number of tiles is a power
 *     of 2 (else within an ulp).
 *   - g(r), the pair correlation of the sphere centres (all sizes together), in bins of dr
 *     from 0 to r_max, r in units of `unit` (default: the packing's d50 by weight):
 *       g_k = N_k / ((n - 1) / V * shell_k),
 *       N_k = (2 / n) sum over the pairs in bin k of V / gamma(h),
 *     shell_k the volume of the bin's spherical shell, V the box's volume, h the pair's
 *     separation and gamma(h) = prod_a (L_a - |h_a|) the volume of box and box shifted by h
 *     (the translation edge correction, Ohser & Stoyan 1981). N_k is the mean number of
 *     other centres in the shell around a sphere, corrected for the shell parts outside the
 *     box: a perfect lattice gives exactly its coordination shells (6, 12, 8 for simple
 *     cubic), and uniform random points (a binomial process) have E g_k = 1 exactly.
 *     Why this correction: the paper's sample is a 0.5 m cube, about 10 d50 across, so
 *     minus-sampling (reference spheres at least r_max from every wall) leaves no sphere at
 *     all at r_max = 5 d50, and 6 % of them at 3 d50; the isotropic (Ripley) correction
 *     needs, per sphere and per bin, the part of a sphere surface inside the box (piecewise,
 *     costly);
 *     the translation weight is exact for a box, costs a product and a division per pair,
 *     and uses every pair. Its cost is variance at large r, where gamma is small: r_max is
 *     held to 3/4 of the box's shortest side (weights at most 64). What no correction can do
 *     is make a bounded sample stationary: S0 is layered at its walls and not uniform (the
 *     fines settle: its lowest fifth holds 1.3 times the centres of each fifth above), and
 *     its g(r) is that of the sample as it is: beyond 1 d50 it averages 0.97 (paper's S0,
 *     seed 7; 0.99 for seed 8) where a stationary packing's would be 1.
 *     Each bin also has its pair count (uncorrected) and the counting error g_k / sqrt(pairs):
 *     the noise of that bin for a random structure (correlated copies, as in a tiling, are
 *     not independent draws: the difference of a tiling from its sample is not noise; and in
 *     a bounded box the shells of spheres near walls are partly empty, which adds variance:
 *     an ideal gas scatters up to 1.6 times the counting error, docs/design/transfer.md).
 *   - g_mirror(r): the same with the walls as mirrors, as the flip continues a packing. Every
 *     sphere is a reference with its whole shell; its neighbours are the other spheres and
 *     the images of all spheres (itself included) across the walls (x -> -x or 2 L - x on
 *     each axis; with r_max <= 3/4 L no farther image is in reach), and
 *       g_mirror_k = (count_k / n) / (n / V * shell_k).
 *     A flip tiling continued by mirrors is the infinite tiling of its sample, whatever its
 *     number of tiles: g_mirror is the same for S0 and every tiling of it (up to the rounding
 *     of the mirrored coordinates, which may move a pair across a bin edge: bit for bit on
 *     S0 of the paper and its 2 x 2 x 2 and 4 x 4 x 4 tilings), and S0's
 *     g_mirror is the g(r) that its tilings tend to as they grow (their outer walls an
 *     ever smaller part). g_mirror - g of S0 is what the flip changes: pairs across the
 *     inner faces, where two wall layers meet face to face and each sphere near a face is
 *     paired with its own image (the wall contacts that become pairs and raise the
 *     sphere-sphere coordination).
 * The contacts come one of three ways (gp_transfer_contacts_kind): this packing's list (e.g.
 * gp_dem3d_contacts, gp_specimen3d.contacts), the sample's list mapped to a flip tiling on
 * the fly (gp_flip_contacts_each: a tiling of millions of spheres never holds its list), or
 * found from the geometry (every overlapping pair, R_i + R_j > |O_i O_j|, and every sphere
 * crossing a wall; for a packing that comes without contacts, e.g. a wrong one on trial).
 *
 * Algorithm and cost: porosity, PSD, d50 (a few passes of a 4096-bin histogram, each pass
 * narrowing to the bin of the median until it holds one value) and the contacts are O(n) or
 * O(contacts); g(r) sorts the centres, and apart the mirror images within r_max of a wall,
 * into one grid of cells at least r_max / 3 wide over the box grown by r_max (core/gp_grid.h,
 * at most 2 (spheres + images) + 64 cells). Each cell meets the cells of its forward
 * half-stencil (of 7 x 7 x 7, those whose nearest points are closer than r_max) for the
 * sphere pairs, each pair once; a cell within r_max of a wall also meets the images in its
 * full stencil. O(n rho r_max^3) time (1.3 s of one core for the 155,520 spheres of the
 * paper's 4 x 4 x 4 tiling at r_max = 5 d50: 85 million pairs), O(n) memory (centres and
 * images, 24 bytes each, and a cell index and the images' first copy while sorting; a
 * histogram a thread). The pair weights are summed as
 * integers (multiples of 2^-56; w <= 64), the counts too: every sum is exact and does not
 * depend on the order, so g(r) is the same bit for bit for any thread count, and equal to a
 * brute-force O(n^2) loop over the same pairs (test_transfer). Figures:
 * docs/design/transfer.md.
 *
 * Invariants: a side is a pure function of the packing and the params (threads and cancel
 * excepted); compare is symmetric. Ownership: inputs are only read; a side and a diff are
 * plain structs the caller owns (fixed-size arrays, nothing to free); scratch is freed before
 * return. Thread safety: no state; concurrent calls are safe. params.threads runs the g(r)
 * pass on a team of its own (gp_team); *params.cancel is read between pieces of work
 * (GP_ERR_CANCELLED, nothing left allocated).
 */
#ifndef GP_TRANSFER_H
#define GP_TRANSFER_H

#include <stddef.h>
#include <stdint.h>

#include "gp_dem3d.h" /* gp_contact3d */
#include "gp_error.h"

#define GP_TRANSFER_MAX_SIEVES 32
#define GP_TRANSFER_MAX_BINS 512

typedef enum gp_transfer_contacts_kind {
    GP_TRANSFER_CONTACTS_GIVEN = 0, /* contacts[ncontacts] are this packing's (j < 0: walls
                                       of this box) */
    GP_TRANSFER_CONTACTS_FLIPPED,   /* contacts[ncontacts] are the sample's (n / tiles spheres):
                                       this packing is its flip tiling by packing.tiles, and
                                       the tiling's contacts are streamed (gp_flip_contacts_each) */
    GP_TRANSFER_CONTACTS_GEOMETRIC  /* none given: the overlapping pairs and wall crossings of
                                       the spheres (gp_dem3d_find_pairs, gap 0) */
} gp_transfer_contacts_kind;

typedef struct gp_transfer_packing {
    const double *xyzr;  /* n spheres: x, y, z, r (r >= 0) */
    size_t n;            /* >= 2 */
    double box[3];       /* the box [0, box] (the tiled box for a tiling) */
    int tiles[3];        /* a flip tiling (gp_flip_tile's sphere order t n0 + i): each copy is
                            clipped to its own tile for the porosity; {0, 0, 0} or {1, 1, 1}:
                            not a tiling, spheres clipped to the box */
    gp_transfer_contacts_kind contact_kind;
    const gp_contact3d *contacts; /* GIVEN, FLIPPED; NULL when ncontacts is 0 */
    size_t ncontacts;
} gp_transfer_packing;

typedef struct gp_transfer_params {
    const double *sieve; /* sieve diameters (m), strictly increasing, > 0 (may be NULL: no PSD) */
    size_t nsieve;       /* <= GP_TRANSFER_MAX_SIEVES */
    double unit;         /* the length unit of r (m); 0 = the packing's d50 by weight. Give both
                            packings the same unit to compare them in metres. */
    double r_max;        /* in units (5); r_max * unit <= 3/4 of the box's shortest side */
    double dr;           /* bin width in units (0.05); ceil(r_max / dr) <= GP_TRANSFER_MAX_BINS */
    int threads;         /* for g(r); 0 = 1. The results do not depend on it. */
    const volatile int *cancel; /* may be NULL */
} gp_transfer_params;

/* No sieve, unit 0 (d50), r_max 5, dr 0.05, one thread, no cancel flag. */
void gp_transfer_params_defaults(gp_transfer_params *p);

typedef struct gp_transfer_side {
    size_t n;
    double box[3];
    double porosity;
    size_t contacts;             /* sphere-sphere */
    size_t wall_contacts;
    double coordination;         /* (2 contacts + wall_contacts) / n */
    double coordination_spheres; /* 2 contacts / n */
    double fabric[3][3];         /* Eq. 14 (gp_dem3d_fabric's weights) */
    double d50;                  /* by weight, m */
    double d_min, d_max;         /* m */
    size_t nsieve;
    double sieve[GP_TRANSFER_MAX_SIEVES];      /* m */
    double psd_number[GP_TRANSFER_MAX_SIEVES]; /* percent passing */
    double psd_weight[GP_TRANSFER_MAX_SIEVES];
    double unit;                 /* m: r = (k + 1/2) dr unit at the middle of bin k */
    double dr;                   /* in units */
    double r_max;                /* nbins dr, in units */
    size_t nbins;
    double g[GP_TRANSFER_MAX_BINS];
    double g_err[GP_TRANSFER_MAX_BINS];      /* counting error g / sqrt(pairs) (0: no pair) */
    double neighbours[GP_TRANSFER_MAX_BINS]; /* N_k: mean other centres per sphere in the bin */
    uint64_t pairs[GP_TRANSFER_MAX_BINS];    /* pairs with their separation in the bin */
    double g_mirror[GP_TRANSFER_MAX_BINS];   /* g with the walls as mirrors (see above) */
} gp_transfer_side;

/* The figures of one packing into *out. GP_ERR_INVALID (names the argument: n, box, a
 * sphere, a contact's index, tiles, sieve, unit, r_max, dr, threads), GP_ERR_NOMEM,
 * GP_ERR_CANCELLED; *out is filled only on GP_OK. */
gp_status gp_transfer_measure(const gp_transfer_packing *packing, const gp_transfer_params *params,
                              gp_transfer_side *out, gp_error *err);

typedef struct gp_transfer_diff {
    double porosity;             /* |b - a| */
    double coordination;
    double coordination_spheres;
    double fabric;               /* max over the nine components */
    double fabric_diagonal;      /* max over xx, yy, zz */
    double d50;                  /* m */
    double psd_number;           /* max over the sieves, percentage points */
    double psd_weight;
    double rdf;                  /* max over the bins of |g_b - g_a| */
    double rdf_r;                /* the middle of that bin, in units */
    double rdf_rms;              /* root mean square of g_b - g_a over the bins */
    double rdf_z;                /* max over the bins with pairs of |g_b - g_a| / sqrt(g_err_a^2
                                    + g_err_b^2): the difference in counting errors, a yardstick
                                    (a tiling and its sample are not independent draws) */
    double rdf_mirror;           /* max over the bins of |g_mirror_b - g_mirror_a| */
} gp_transfer_diff;

/* The largest difference of each figure between a and b. The two sides must have the same
 * sieves and the same bins (nbins, dr in units); g is compared bin by bin in units (in
 * metres when both were measured with the same unit). GP_ERR_INVALID otherwise. */
gp_status gp_transfer_compare(const gp_transfer_side *a, const gp_transfer_side *b,
                              gp_transfer_diff *d, gp_error *err);

#endif /* GP_TRANSFER_H */
