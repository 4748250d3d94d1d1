/* json_scan.h -- reading parts of a large JSON text without parsing it, or holding it, whole.
 *
 * A stored result is one JSON object of up to hundreds of MB whose bulk is a few per-item
 * arrays ("grains", "cells", "spheres", "contacts"). The scanner finds the byte span of each
 * top-level member, walks the elements of an array one at a time and parses only the spans
 * asked for (with jansson), so that reading a result's statistics or drawing its cells costs
 * the size of those parts, not of the result. The text is read at offsets through a byte
 * source (a memory buffer, an SQLite incremental blob) with one 64 KiB cache.
 *
 * The scanner trusts the text to be JSON (the daemon wrote it) and does not validate it, but
 * on any text it stays within the source, always advances, and reports malformed structure
 * as an error (-1) rather than guessing. Not thread-safe per scanner; scanners are
 * independent. */
#ifndef GPD_JSON_SCAN_H
#define GPD_JSON_SCAN_H

#include <stddef.h>
#include <stdint.h>

#include <jansson.h>

/* Reads n bytes at offset off into dst; returns 0 on success. */
typedef int (*js_read_fn)(void *user, uint64_t off, void *dst, size_t n);

typedef struct js_source {
    js_read_fn read;
    void *user;
    uint64_t size; /* bytes of text */
} js_source;

/* A source over text in memory (which must outlive the source's use). */
js_source json_scan_memory_source(const char *text, size_t len);

typedef struct js_scan js_scan;

/* NULL on out of memory. The source must stay valid until json_scan_close. */
js_scan *json_scan_open(const js_source *src);
void json_scan_close(js_scan *s);

/* Calls fn for each member of the top-level object, in text order: key (as written, escapes
 * kept, cut at 255 bytes), the offset of the member (its key's opening quote) and the span
 * [voff, vend) of its value. fn returns 0 to go on, anything else to stop (json_scan_members then
 * returns that value). Returns 0 after the last member, -1 when the text is not an object, is
 * malformed or cannot be read. */
typedef int (*js_member_fn)(void *user, const char *key, uint64_t moff, uint64_t voff,
                            uint64_t vend);
int json_scan_members(js_scan *s, js_member_fn fn, void *user);

/* Walks the array whose text starts at off (its '['): json_scan_array_begin() returns 0 (or -1 when
 * there is no array there), then each json_scan_array_next() gives the span [*eoff, *eend) of the
 * next element and returns 1, or 0 after the last one, or -1 on malformed text. Walking again
 * is calling json_scan_array_begin() again. */
int json_scan_array_begin(js_scan *s, uint64_t off);
int json_scan_array_next(js_scan *s, uint64_t *eoff, uint64_t *eend);

/* The text of [off, end), NUL-terminated, in the scanner's buffer (valid until the next
 * json_scan_span or json_scan_load); NULL when it cannot be read or on out of memory. The buffer grows to
 * the largest span read and is kept (up to 1 MiB) for the next call. */
const char *json_scan_span(js_scan *s, uint64_t off, uint64_t end);

/* The value in [off, end), parsed (a new reference), or NULL when it is not JSON or cannot be
 * read (through json_scan_span). */
json_t *json_scan_load(js_scan *s, uint64_t off, uint64_t end);

/* Copies [off, end) into dst (end - off bytes); 0 on success. */
int json_scan_copy(js_scan *s, uint64_t off, uint64_t end, char *dst);

/* The text of an object with the top-level members of src except those named in skip (a
 * NULL-terminated list), copied verbatim in their order: e.g. a result without its per-item
 * arrays. malloc'ed and NUL-terminated (length in *len when len is not NULL); NULL when src
 * is not an object, is malformed, cannot be read, or on out of memory. Memory: the output
 * plus the scanner's cache. When spans is not NULL, spans[i] gets the span [off, end) of the
 * value of skip[i] in src ({0, 0} when src has no such member). */
char *json_scan_object_without(const js_source *src, const char *const *skip, size_t *len,
                        uint64_t (*spans)[2]);

#endif /* GPD_JSON_SCAN_H */
