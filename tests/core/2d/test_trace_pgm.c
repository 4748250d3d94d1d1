/* test_trace_pgm.c -- the PGM header reader and parser of gp_trace against hostile files:
 * comments and every kind of whitespace in the header, zero-padded and huge numbers, zero
 * sides, maxval 0 and 65536, truncated data and data too short for the bytes a value takes,
 * a header that claims a gigapixel image over a few bytes, and the agreement of
 * gp_trace_pgm_header (the daemon's size check) with gp_trace_pgm_parse. */
#include "gp_test.h"
#include "gp_trace.h"

#include <stdio.h>
#include <string.h>

/* the header of a literal (sizeof - 1: the bytes may hold NULs) */
#define HEADER(lit, hd, e) gp_trace_pgm_header(lit, sizeof lit - 1, hd, e)
#define PARSE(lit, g, e) gp_trace_pgm_parse(lit, sizeof lit - 1, g, e)

/* parse refuses buf with a message holding `says`, and leaves nothing behind */
static void check_refused(const char *buf, size_t len, const char *says)
{
    gp_trace_gray g;
    gp_error e;
    gp_error_clear(&e);
    gp_status st = gp_trace_pgm_parse(buf, len, &g, &e);
    CHECK(st == GP_ERR_INVALID);
    CHECK(g.v == NULL && g.w == 0 && g.h == 0 && g.maxval == 0);
    if (!strstr(e.message, says)) {
        fprintf(stderr, "%.*s: message \"%s\" does not say \"%s\"\n", (int)(len < 40 ? len : 40),
                buf, e.message, says);
        CHECK(0);
    }
    gp_trace_gray_free(&g);
}
#define REFUSED(lit, says) check_refused(lit, sizeof lit - 1, says)

/* the header reader and the parser agree on buf: the same refusal, or the same sizes */
static void check_agree(const char *buf, size_t len)
{
    gp_trace_pgm_info hd;
    gp_trace_gray g;
    gp_error eh, ep;
    gp_status sh = gp_trace_pgm_header(buf, len, &hd, &eh);
    gp_status sp = gp_trace_pgm_parse(buf, len, &g, &ep);
    if (sh != GP_OK) {
        CHECK(sp == sh && !strcmp(eh.message, ep.message));
        CHECK(hd.w == 0 && hd.h == 0 && hd.maxval == 0);
    } else if (sp == GP_OK) {
        CHECK(g.w == hd.w && g.h == hd.h && g.maxval == hd.maxval);
    }
    gp_trace_gray_free(&g);
}

static void test_comments_and_whitespace(void)
{
    gp_trace_gray g;
    gp_error e;
    /* comments after the magic, after each number, and before the raster's one whitespace
     * byte (as netpbm reads it) */
    const char c[] = "P5#magic\n2#w\n 1 # h\n255# the raster follows\n\x10\x20";
    CHECK(PARSE(c, &g, &e) == GP_OK);
    CHECK(g.w == 2 && g.h == 1 && g.v && g.v[0] == 16 && g.v[1] == 32);
    gp_trace_gray_free(&g);
    /* tabs, vertical tabs and form feeds separate as spaces do */
    const char t[] = "P5\t3\x0b" "1\x0c" "255\t\x01\x02\x03";
    CHECK(PARSE(t, &g, &e) == GP_OK);
    CHECK(g.w == 3 && g.v && g.v[2] == 3);
    gp_trace_gray_free(&g);
    /* CR LF line ends: a P5 header ends at its one whitespace byte, the CR, so the LF is the
     * first value (netpbm's reading too) */
    const char crlf[] = "P5\r\n2 1\r\n255\r\n\x07";
    CHECK(PARSE(crlf, &g, &e) == GP_OK);
    CHECK(g.v && g.v[0] == '\n' && g.v[1] == 7);
    gp_trace_gray_free(&g);
    /* P2 with CR LF everywhere and a comment ended by a lone CR */
    const char p2[] = "P2\r\n# made on another system\r3 1\r\n9\r\n1 2\r\n3\r\n";
    CHECK(PARSE(p2, &g, &e) == GP_OK);
    CHECK(g.v && g.v[0] == 1 && g.v[2] == 3);
    gp_trace_gray_free(&g);
    /* P2 values may be zero-padded into columns; header numbers may not (below) */
    const char pad[] = "P2 3 1 255\n007 000 255\n";
    CHECK(PARSE(pad, &g, &e) == GP_OK);
    CHECK(g.v && g.v[0] == 7 && g.v[1] == 0 && g.v[2] == 255);
    gp_trace_gray_free(&g);
    /* a comment with no line end swallows the rest: no header */
    REFUSED("P5 2 1 # 255\n", "maxval is missing");
    /* a NUL or a letter is no separator */
    REFUSED("P5 2\0" "1 255\n\x01\x02", "width is not followed by whitespace");
    REFUSED("P2 2x 1 5 1 1", "width is not followed by whitespace");
    REFUSED("P5\x01" "2 1 255\n\x01\x02", "no whitespace after the magic number");
    /* a P5 header ends with whitespace, not the end of the file */
    REFUSED("P5 1 1 255", "no whitespace after maxval");
}

static void test_numbers(void)
{
    /* the bypass of a size check that read 12 digits while the parser read them all: width
     * 3 written as 0000000000003; refused by the one header reader, so any check sees it */
    const char bypass[] = "P5 0000000000003 200000 255\n";
    gp_trace_pgm_info hd;
    gp_error e;
    CHECK(HEADER(bypass, &hd, &e) == GP_ERR_INVALID);
    CHECK(strstr(e.message, "width is zero-padded") != NULL);
    REFUSED("P5 0000000000003 200000 255\n", "width is zero-padded");
    REFUSED("P5 0000000000004096 262144 255\n", "width is zero-padded");
    REFUSED("P5 3 0200 255\n", "height is zero-padded");
    REFUSED("P5 2 1 0255\n\x01\x02", "maxval is zero-padded");
    /* huge numbers: refused at the first digit over the limit, no overflow on the way */
    REFUSED("P5 99999999999999999999999999999999 1 255\n\x01", "width is over 1073741824");
    REFUSED("P5 1 18446744073709551617 255\n\x01", "height is over 1073741824");
    REFUSED("P5 1073741825 1 255\n", "width is over 1073741824");
    REFUSED("P5 65536 65536 255\n", "65536 x 65536 pixels is over 1073741824");
    /* zero sides, maxval 0 and over 65535 */
    REFUSED("P5 0 5 255\n\x00\x00\x00\x00\x00", "a side is 0");
    REFUSED("P2 4 0 255\n", "a side is 0");
    REFUSED("P5 1 1 0\n\x00", "maxval 0");
    REFUSED("P5 1 1 65536\n\x00\x00", "maxval is over 65535");
    REFUSED("P2 1 1 70000 1", "maxval is over 65535");
    /* no sign, no number */
    REFUSED("P5 -3 2 255\n\x00\x00\x00\x00\x00\x00", "width is missing or not a number");
    REFUSED("P5 +3 2 255\n\x00\x00\x00\x00\x00\x00", "width is missing or not a number");
    REFUSED("P5", "no whitespace after the magic number");
    REFUSED("P3 1 1 255\n", "not a PGM file");
    /* the largest header the reader takes: GP_TRACE_MAX_PIXELS pixels, maxval 65535 */
    const char most[] = "P5 32768 32768 65535\n";
    CHECK(HEADER(most, &hd, &e) == GP_OK);
    CHECK(hd.w == 32768 && hd.h == 32768 && hd.maxval == 65535 && hd.binary == 1);
    CHECK(hd.data == sizeof most - 1 && hd.data_min == (size_t)2 * 32768 * 32768);
    /* a single 0 is a number (then a zero side), and so is 1 */
    REFUSED("P5 0 0 1\n", "a side is 0");
    const char one[] = "P5 1 1 1\n\x01";
    gp_trace_gray g;
    CHECK(PARSE(one, &g, &e) == GP_OK && g.v && g.v[0] == 1);
    gp_trace_gray_free(&g);
}

static void test_data_length(void)
{
    gp_trace_gray g;
    gp_error e;
    /* a gigapixel header over four bytes: refused as truncated before any allocation (an
     * allocation of 2 GiB would fail under ASan's allocator limits or take the memory) */
    REFUSED("P5 32768 32768 255\n\x00\x00\x00\x00", "truncated");
    REFUSED("P5 32768 32768 65535\n", "truncated: 32768 x 32768 values take 2147483648 bytes");
    /* a byte short, 8 and 16 bits */
    REFUSED("P5 3 2 255\n\x01\x02\x03\x04\x05", "truncated: 3 x 2 values take 6 bytes, 5 given");
    REFUSED("P5 2 1 256\n\x01\x02\x03", "take 4 bytes, 3 given");
    /* the data of an 8-bit image under a 16-bit maxval: a byte per value where two are due */
    REFUSED("P5 2 2 1000\n\x01\x02\x03\x04", "take 8 bytes, 4 given");
    /* P2: at least a digit per value and a blank between two */
    REFUSED("P2 3 2 9\n1 2 3 4 5", "take at least 11 bytes");
    REFUSED("P2 1 1 5", "take at least 1 bytes, 0 given");
    /* long enough for the bound, but a value missing or over maxval */
    REFUSED("P2 3 2 9\n1 2 3 4 5    ", "value 5 of 6 is missing");
    REFUSED("P2 2 1 5 1 6", "value 1 = 6 exceeds maxval 5");
    REFUSED("P5 1 1 1000\n\x03\xe9", "value 0 = 1001 exceeds maxval 1000");
    /* exactly the bytes due, and bytes after them (a second image is not read) */
    const char exact[] = "P5 2 1 1000\n\x03\xe8\x00\x07";
    CHECK(PARSE(exact, &g, &e) == GP_OK && g.v && g.v[0] == 1000 && g.v[1] == 7);
    gp_trace_gray_free(&g);
    const char more[] = "P5 2 1 255\n\x01\x02P5 2 1 255\n\x03\x04";
    CHECK(PARSE(more, &g, &e) == GP_OK && g.v && g.v[0] == 1 && g.v[1] == 2);
    gp_trace_gray_free(&g);
    /* the header's data offset and the bytes it asks for */
    gp_trace_pgm_info hd;
    const char p2[] = "P2 3 2 9 # c\n1 2 3 4 5 6";
    CHECK(HEADER(p2, &hd, &e) == GP_OK);
    CHECK(hd.binary == 0 && hd.data == 8 && hd.data_min == 11);
    const char p5[] = "P5 3 2 300\n";
    CHECK(HEADER(p5, &hd, &e) == GP_OK);
    CHECK(hd.binary == 1 && hd.data == sizeof p5 - 1 && hd.data_min == 12);
}

/* every prefix of a few files: the header reader and the parser agree on each, and nothing
 * reads past the end (ASan in the sanitized build) */
static void test_prefixes(void)
{
#define FILE_OF(lit) {lit, sizeof lit - 1}
    static const struct {
        const char *b;
        size_t n;
    } files[] = {
        FILE_OF("P5\n# c\n3 2\n255\n\x01\x02\x03\x04\x05\x06"),
        FILE_OF("P2 # c\n3 2 # d\n9\n1 2 3\n4 5 6\n"),
        FILE_OF("P5 2 1 1000\n\x03\xe8\x00\x07"),
        FILE_OF("P5 0000000000003 200000 255\n\x01\x02"),
        FILE_OF("P5\r\n2 1\r\n255# c\r\x07\x08"),
    };
    for (size_t f = 0; f < sizeof files / sizeof *files; f++)
        for (size_t n = 0; n <= files[f].n; n++) {
            char buf[64];
            memcpy(buf, files[f].b, n);
            check_agree(buf, n);
        }
    gp_trace_pgm_info hd;
    gp_error e;
    CHECK(gp_trace_pgm_header(NULL, 10, &hd, &e) == GP_ERR_INVALID);
    CHECK(gp_trace_pgm_header("P5 1 1 1\n\x01", 10, NULL, &e) == GP_ERR_INVALID);
}

int main(void)
{
    test_comments_and_whitespace();
    test_numbers();
    test_data_length();
    test_prefixes();
    return gp_test_summary();
}
