/* shapes.h -- POST /v1/shapes/analyze: the Fourier spectrum and descriptors of real
 * grain outlines, answered at once (no job), so that a user sees what a job with
 * shape.outlines would make before submitting it.
 *
 * The body is one of
 *   {"outlines": [[[x, y], ...], ...]}   (api.md: 10 to 10,000 closed outlines)
 *   {"image": {"pgm": "<base64 of a P2/P5 PGM>", "grains": "light" | "dark",
 *              "threshold": t, "pixel_size": s}}      (this daemon's extension: README)
 * with an optional "contour_points" (the spec's: rays of the analysis, contour_points / 2
 * modes; default 128, as a job).
 *
 * Outlines are validated by the spec's own code: the body's outlines become a spec's
 * shape.outlines (gp_spec_with_defaults), so that the bounds (10 .. 10,000 outlines, 3 ..
 * 10,000 points each, 1,000,000 vertices in all) and the refusal of an outline that is not
 * star-shaped from any interior point, crosses itself or has no area are exactly those of a
 * job submit, at the same pointers with "/shape" dropped (/outlines, /outlines/i,
 * /outlines/i/k). Why refuse rather than analyse the rest: the same outlines submitted as a
 * job would be refused, and the answer is meant to preview that job. A traced image is
 * different: its outlines are the tracer's, not the user's to fix, so an outline that
 * cannot be analysed is left out and reported (refused, by index, with its reason and its
 * first pixel) and the image fails only when fewer than 10 remain.
 *
 * The answer (200):
 *   {"outlines": n (given, or traced), "analysed": m, "described": k, "modes": M,
 *    "contour_points": np,
 *    "spectrum": {"mean": [D0 = 1, D1, ..., D_{M-1}], "cov": [M], "sd": [M]},
 *    "descriptors": {"elongation": {"mean", "sd"}, "roundness": {..}, "circularity": {..},
 *                    "regularity": {..}},
 *    "reversed": [indices given clockwise, analysed reversed],
 *    "pole_moved": [indices not star-shaped from their centroid: analysed about the centroid
 *                   of their kernel],
 *    "deduplicated": [indices with repeated points dropped],
 *    "no_descriptors": [indices analysed whose Fourier grain could not be described],
 *    "refused": [{"index": i, "code": "not_star" | "invalid" | "degenerate", "message": ..,
 *                 "pixel": [col, row] (traced outlines: the grain's first pixel, row 0 at
 *                 the top)}],
 *    "traced": {"grains": n, "components": c, "skipped_border": b, "skipped_small": s,
 *               "min_pixels": 100, "width": w, "height": h, "pixel_size": ps,
 *               "threshold": t, "grains_are": "light" | "dark",
 *               "diameter": {"mean", "sd"} (area-equivalent, in pixel_size units)}
 *               (image only)}
 * Errors: the API's error object: 400 invalid_json (unreadable or empty body), 422
 * invalid_spec or too_large with the pointer of the field at fault, 500 internal.
 * Work: the spec check (linear in the vertices) and one analysis per outline with its
 * descriptors (~0.5 ms each at 128 rays: 10,000 outlines in about 5 s, one thread; the cost
 * grows as contour_points^2, so outlines x (contour_points / 128)^2 is bounded: 422 too_large
 * at /contour_points above 40,000); an image is O(pixels) to trace (at most
 * SHAPES_IMAGE_SIDE_MAX a side, ~11 bytes a pixel of scratch).
 * Thread safety: no state; called from the offload pool (offload.h), several at once. */
#ifndef GPD_SHAPES_H
#define GPD_SHAPES_H

#include <stddef.h>

#include <jansson.h>

/* an image's width and height at most (pixels): 16.7 Mpixel, ~190 MB of scratch at worst */
#define SHAPES_IMAGE_SIDE_MAX 4096

/* A request whose client may leave: gone(arg) says it has (may be NULL: never). */
typedef struct gpd_shapes_client {
    int (*gone)(void *arg);
    void *arg;
} gpd_shapes_client;

/* *status of an analysis stopped because its client left: nobody reads the answer (NULL) */
#define SHAPES_CLIENT_GONE 0

/* The answer to a POST /v1/shapes/analyze of body (len bytes, need not be NUL-terminated):
 * the answer or the error object, with its HTTP status in *status; NULL when out of memory
 * (*status 500). The analysis asks client->gone every GP_OUTLINE_REPORT_EVERY outlines and
 * stops when it says so (NULL, *status SHAPES_CLIENT_GONE). The caller owns the result. */
json_t *gpd_shapes_analyze(const char *body, size_t len, const gpd_shapes_client *client,
                           int *status);

#endif /* GPD_SHAPES_H */
