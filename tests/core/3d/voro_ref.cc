// voro_ref.cc -- the reference for test_voronoi3d_voro and bench_voronoi3d: voro++'s
// tessellation of seeds in a box (walls on every side, not periodic).
//
// Input (the file named by argv[1], or stdin): "xlo ylo zlo xhi yhi zhi", then one seed per
// line "x y z". Output (stdout), one line per seed in input order:
//     i volume faces area_1 ... area_faces
// (volume and areas with 17 significant digits). On stderr: the time voro++ took to insert
// the seeds and compute every cell ("voro++ seconds <t>"). Exit status 1 on bad input or a
// cell voro++ could not compute.
#include <chrono>
#include <cmath>
#include <cstdio>
#include <vector>

#include <voro++/voro++.hh>

int main(int argc, char **argv)
{
    FILE *in = argc > 1 ? std::fopen(argv[1], "r") : stdin;
    if (!in) {
        std::fprintf(stderr, "voro_ref: cannot open %s\n", argv[1]);
        return 1;
    }
    double lo[3], hi[3];
    if (std::fscanf(in, "%lf %lf %lf %lf %lf %lf", lo, lo + 1, lo + 2, hi, hi + 1, hi + 2) != 6) {
        std::fprintf(stderr, "voro_ref: expected the box on the first line\n");
        return 1;
    }
    std::vector<double> s;
    double p[3];
    while (std::fscanf(in, "%lf %lf %lf", p, p + 1, p + 2) == 3) s.insert(s.end(), p, p + 3);
    size_t n = s.size() / 3;
    if (n == 0) {
        std::fprintf(stderr, "voro_ref: no seeds\n");
        return 1;
    }
    // about 5 seeds per block, as voro++'s documentation advises
    double vol = (hi[0] - lo[0]) * (hi[1] - lo[1]) * (hi[2] - lo[2]);
    double h = std::cbrt(5.0 * vol / (double)n);
    int nb[3];
    for (int a = 0; a < 3; a++) {
        nb[a] = (int)((hi[a] - lo[a]) / h);
        if (nb[a] < 1) nb[a] = 1;
    }
    std::vector<double> volume(n, -1);
    std::vector<std::vector<double>> areas(n);
    auto t0 = std::chrono::steady_clock::now();
    voro::container con(lo[0], hi[0], lo[1], hi[1], lo[2], hi[2], nb[0], nb[1], nb[2], false,
                        false, false, 8);
    for (size_t i = 0; i < n; i++) con.put((int)i, s[3 * i], s[3 * i + 1], s[3 * i + 2]);
    voro::c_loop_all loop(con);
    voro::voronoicell c;
    if (loop.start()) do {
            if (con.compute_cell(c, loop)) {
                int id = loop.pid();
                volume[id] = c.volume();
                c.face_areas(areas[id]);
            }
        } while (loop.inc());
    double secs = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    std::fprintf(stderr, "voro++ seconds %.6f\n", secs);
    int bad = 0;
    for (size_t i = 0; i < n; i++) {
        if (volume[i] < 0) {
            std::fprintf(stderr, "voro_ref: no cell for seed %zu\n", i);
            bad = 1;
            continue;
        }
        std::printf("%zu %.17g %zu", i, volume[i], areas[i].size());
        for (double a : areas[i]) std::printf(" %.17g", a);
        std::printf("\n");
    }
    return bad;
}
