"""The PGM header of POST /v1/shapes/analyze's image against the real daemon: the side limit
(4,096 pixels) is checked on the header as the parser reads it, so a header cannot pass the
check with one size and be parsed with another.

- a zero-padded side (P5 0000000000003 200000 255: three pixels wide to a reader that counts
  digits, the first twelve digits zero to one that stops after twelve) is refused, 422
  invalid_spec at /image/pgm, and so is a padded 4096 x 262144 one (a gigapixel);
- the same sizes without padding are over the side limit: 422 too_large at /image/pgm;
- huge numbers, zero sides, maxval 0 and 65536, truncated data, 8-bit data under a 16-bit
  maxval: 422 invalid_spec at /image/pgm, naming the fault; a header that claims the largest
  image allowed over a few bytes is refused as truncated;
- headers with comments, tabs, vertical tabs, form feeds and CR LF line ends are read: those
  images (no grain in them) get as far as the tracer, 422 at /image;
and the daemon stays healthy and exits cleanly (no sanitizer report) after all of them."""
import base64
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import gpd  # noqa: E402

PATH = "/v1/shapes/analyze"


def analyze(d, pgm):
    body = {"image": {"pgm": base64.b64encode(pgm).decode()}}
    return d.json("POST", PATH, body, timeout=60)


def expect(d, pgm, code, pointer, says):
    st, _, j = analyze(d, pgm)
    assert st == 422, (pgm[:40], st, j)
    gpd.check_error_body(st, j, code, pointer)
    assert says in j["error"]["message"], (pgm[:40], j, says)
    return j


def test_side_limit_bypass(env):
    d = env.daemon(workers=1)
    # the bypass itself, with data after it, and a padded header claiming a gigapixel
    expect(d, b"P5 0000000000003 200000 255\n" + bytes(600), "invalid_spec", "/image/pgm",
           "width is zero-padded")
    expect(d, b"P5 0000000000004096 262144 255\n", "invalid_spec", "/image/pgm",
           "width is zero-padded")
    expect(d, b"P5 3 000000000000200000 255\n", "invalid_spec", "/image/pgm",
           "height is zero-padded")
    # the same sizes written plainly: over the side limit
    j = expect(d, b"P5 3 200000 255\n" + bytes(600), "too_large", "/image/pgm", "3 x 200000")
    assert "4096 x 4096" in j["error"]["message"], j
    expect(d, b"P5 4097 1 255\n" + bytes(4097), "too_large", "/image/pgm", "4097 x 1")
    assert d.json("GET", "/v1/health")[0] == 200
    assert d.stop() == 0, "daemon did not exit cleanly:\n" + d.read_log()


def test_hostile_headers(env):
    d = env.daemon(workers=1)
    cases = [
        (b"P5 99999999999999999999999999 1 255\n\x00", "width is over"),
        (b"P5 1 18446744073709551617 255\n\x00", "height is over"),
        (b"P5 0 5 255\n" + bytes(5), "a side is 0"),
        (b"P5 5 5 0\n" + bytes(25), "maxval 0"),
        (b"P5 5 5 65536\n" + bytes(50), "maxval is over 65535"),
        (b"P5 5 5 0255\n" + bytes(25), "maxval is zero-padded"),
        (b"P5 -5 5 255\n" + bytes(25), "width is missing or not a number"),
        # the largest image allowed, claimed over 16 bytes: refused before it is allocated
        (b"P5 4096 4096 65535\n" + bytes(16), "truncated: 4096 x 4096 values take 33554432"),
        (b"P5 5 5 255\n" + bytes(24), "take 25 bytes, 24 given"),
        # 8-bit data under a 16-bit maxval: a byte per value where two are due
        (b"P5 5 5 1000\n" + bytes(25), "take 50 bytes, 25 given"),
        (b"P2 5 5 255\n0 0 0", "take at least 49 bytes"),
        (b"P5 5 5 255", "no whitespace after maxval"),
        (b"P5 5\x005 255\n" + bytes(25), "width is not followed by whitespace"),
    ]
    for pgm, says in cases:
        expect(d, pgm, "invalid_spec", "/image/pgm", says)
    # read, then traced: no grain in a flat image, so the answer is the tracer's, at /image
    read = [
        b"P5\n# a comment\n5 5 # w h\n255\n" + bytes(25),
        b"P5\t5\x0b5\x0c255\t" + bytes(25),
        b"P5\r\n5 5\r\n255\r\n" + bytes(25),
        b"P5 5 5 255# the raster follows\n" + bytes(25),
        b"P2\r\n# CR LF\r\n5 5\r\n255\r\n" + b"0 0 0 0 0\r\n" * 5,
        b"P2 5 5 255\n" + b"000 000 000 000 000\n" * 5,
    ]
    for pgm in read:
        expect(d, pgm, "invalid_spec", "/image", "0 grains traced")
    assert d.json("GET", "/v1/health")[0] == 200
    assert d.stop() == 0, "daemon did not exit cleanly:\n" + d.read_log()


if __name__ == "__main__":
    gpd.main([test_side_limit_bypass, test_hostile_headers])
