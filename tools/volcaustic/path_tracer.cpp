// An independent CPU path tracer for scenes/tungsten/volumetric-caustic with
// integrator.type path_tracer, written from Tungsten 0.2.2's PathTracer / TraceBase: the front
// wall's crossing and every scattering vertex count as bounces (max_bounces 6), light sampling
// with MIS against phase / cosine sampling at medium and Lambert vertices (no light sampling at
// the last bounce), emission counted on a hit only after a specular vertex (or the camera),
// Russian roulette after bounce 2 below throughput 0.1, the ball's inside vacuum, two-sided
// Lambert walls. Prints the mean R + G + B of 16 x 16-pixel blocks of the 256 x 144 image
// (QUARTER=1: 4 x 4 blocks of 64 x 36) with a tent pixel filter of radius 1, the standard error
// from the samples, and how many samples hit the light through a specular chain.
//   g++ -O2 -o path_tracer path_tracer.cpp
//   ./path_tracer SPP bx,by [bx,by ...] | all      (env: LIGHTSCALE, QUARTER, MAXB, INSIDE=gas, PRINTEV)
#include "scene.h"

static int MAXB = 6;  // Tungsten's max_bounces

static V trace(V o, V d, Rng& r, bool& counted) {
    V thr = {1, 1, 1}, L = {0, 0, 0};
    // camera ray: vacuum to the front wall (forward): bounce 0 is that crossing
    Hit h;
    if (!intersect(o, d, 1e30, h)) return L;
    if (h.prim < 0 || quads[h.prim].kind != FORWARD) return L;
    int bounce = 1;
    o = h.p; bool inGas = true; bool wasSpecular = true;
    while (bounce < MAXB) {
        if (!intersect(o, d, 1e30, h)) break;
        bool scattered = false;
        if (inGas) {
            double t = -std::log(1 - r.next());
            if (t < h.t) {
                scattered = true;
                V p = o + d * t;
                wasSpecular = false;
                if (bounce < MAXB - 1) {
                    // volume light sample
                    V wi; double dist, pdf;
                    if (sampleLight(p, r, wi, dist, pdf)) {
                        double tr = shadow(p, wi, dist);
                        if (tr > 0) L = L + mul(thr, Le) * (tr / (4 * PI) / pdf * power(pdf, 1 / (4 * PI)));
                    }
                    // phase sample
                    double u1 = r.next(), u2 = r.next();
                    double ct = 1 - 2 * u1, st = std::sqrt(std::max(0.0, 1 - ct * ct));
                    V w = {st * std::cos(2 * PI * u2), st * std::sin(2 * PI * u2), ct};
                    double tl, lpdf;
                    if (hitLight(p, w, tl, lpdf)) {
                        double tr = shadow(p, w, tl);
                        if (tr > 0) L = L + mul(thr, Le) * (tr * power(1 / (4 * PI), lpdf));
                    }
                }
                double u1 = r.next(), u2 = r.next();
                double ct = 1 - 2 * u1, st = std::sqrt(std::max(0.0, 1 - ct * ct));
                d = {st * std::cos(2 * PI * u2), st * std::sin(2 * PI * u2), ct};
                o = p;
            }
        }
        if (!scattered) {
            if (h.prim == -1) {
                // dielectric ball
                bool front = dot(d, h.n) < 0;
                V n = front ? h.n : h.n * -1;
                double eta = front ? 1 / 1.5 : 1.5;  // n_i / n_t
                double cosI = -dot(d, n);
                double sin2T = eta * eta * (1 - cosI * cosI);
                double F;
                double cosT = 0;
                if (sin2T >= 1) F = 1;
                else {
                    cosT = std::sqrt(1 - sin2T);
                    double rs = (eta * cosI - cosT) / (eta * cosI + cosT);
                    double rp = (cosI - eta * cosT) / (cosI + eta * cosT);
                    F = 0.5 * (rs * rs + rp * rp);
                }
                if (r.next() < F) {
                    d = d + n * (2 * cosI);
                } else {
                    d = norm(d * eta + n * (eta * cosI - cosT));
                    inGas = ballGas ? true : !front;
                }
                wasSpecular = true;
                o = h.p;
            } else {
                const Quad& q = quads[h.prim];
                if (q.kind == LIGHT) {
                    if (wasSpecular && dot(d, q.n) < 0) { L = L + mul(thr, Le); counted = true; }
                    break;
                }
                if (q.kind == FORWARD) break;  // leaving the box: nothing outside
                // lambert, two-sided
                V n = dot(d, q.n) < 0 ? q.n : q.n * -1;
                V p = h.p;
                if (bounce < MAXB - 1) {
                    V wi; double dist, pdf;
                    if (sampleLight(p, r, wi, dist, pdf)) {
                        double c = dot(wi, n);
                        if (c > 0) {
                            double tr = shadow(p, wi, dist);
                            if (tr > 0) L = L + mul(mul(thr, Le), q.albedo) * (tr * c / PI / pdf * power(pdf, c / PI));
                        }
                    }
                    double u1 = r.next(), u2 = r.next();
                    double rr = std::sqrt(u1), ph = 2 * PI * u2;
                    V t, b; frame(n, t, b);
                    V w = t * (rr * std::cos(ph)) + b * (rr * std::sin(ph)) + n * std::sqrt(std::max(0.0, 1 - u1));
                    double tl, lpdf;
                    if (hitLight(p, w, tl, lpdf)) {
                        double tr = shadow(p, w, tl);
                        double bp = dot(w, n) / PI;
                        if (tr > 0) L = L + mul(mul(thr, Le), q.albedo) * (tr * power(bp, lpdf));
                    }
                }
                double u1 = r.next(), u2 = r.next();
                double rr = std::sqrt(u1), ph = 2 * PI * u2;
                V t, b; frame(n, t, b);
                d = t * (rr * std::cos(ph)) + b * (rr * std::sin(ph)) + n * std::sqrt(std::max(0.0, 1 - u1));
                thr = mul(thr, q.albedo);
                wasSpecular = false;
                o = p;
            }
        }
        double q = maxc(thr);
        if (bounce > 2 && q < 0.1) {
            if (r.next() < q) thr = thr * (1 / q);
            else break;
        }
        bounce++;
    }
    return L;
}

int main(int argc, char** argv) {
    int spp = std::atoi(argv[1]);
    if (getenv("MAXB")) MAXB = std::atoi(getenv("MAXB"));
    if (getenv("INSIDE")) ballGas = std::string(getenv("INSIDE")) == "gas";
    buildScene(getenv("LIGHTSCALE") ? std::atof(getenv("LIGHTSCALE")) : 1.0);
    const int Q = getenv("QUARTER") ? 4 : 1, W = 256 / Q, H = 144 / Q, BS = 16 / Q;
    const Camera c;
    const V cam = c.pos, fwd = c.fwd, right = c.right, up = c.up;
    const double plane = c.plane;
    std::vector<std::string> blocks(argv + 2, argv + argc);
    if (blocks.size() == 1 && blocks[0] == "all") {
        blocks.clear();
        for (int by = 0; by < 9; ++by) for (int bx = 0; bx < 16; ++bx) blocks.push_back(std::to_string(bx) + "," + std::to_string(by));
    }
    for (const std::string& blk : blocks) {
        int bx, by;
        std::sscanf(blk.c_str(), "%d,%d", &bx, &by);
        Rng r{0x9E3779B97F4A7C15ull ^ (uint64_t(bx * 131 + by) * 0x2545F4914F6CDD1Dull)};
        for (int i = 0; i < 20; ++i) r.next();
        double sum = 0, sum2 = 0, ssum2 = 0;
        long n = 0, hits = 0;
        for (int py = by * BS; py < by * BS + BS; ++py)
            for (int px = bx * BS; px < bx * BS + BS; ++px) {
                double psum = 0;
                for (int s = 0; s < spp; ++s) {
                    auto tent = [](double u) { return u < 0.5 ? std::sqrt(2 * u) - 1 : 1 - std::sqrt(2 - 2 * u); };
                    double fx = px + 0.5 + tent(r.next()), fy = py + 0.5 + tent(r.next());
                    double u = 2 * fx / W - 1, v = double(H) / W - 2 * fy / W;
                    V d = norm(right * u + up * v + fwd * plane);
                    bool counted = false;
                    V c = trace(cam, d, r, counted);
                    hits += counted;
                    if (counted && getenv("PRINTEV")) std::printf("event %d %d %.1f\n", px, py, (c.x + c.y + c.z) / spp);
                    psum += c.x + c.y + c.z;
                    ssum2 += (c.x + c.y + c.z) * (c.x + c.y + c.z);
                }
                psum /= spp;
                sum += psum; sum2 += psum * psum; ++n;
            }
        double mean = sum / n, var = (sum2 / n - mean * mean) / n;
        double ns = double(n) * spp, svar = (ssum2 / ns - mean * mean) / ns;
        std::printf("  sample-level s.e. %.5f over %.0f samples\n", std::sqrt(svar), ns);
        std::printf("block %d,%d: R+G+B mean %.4f +- %.4f (pixel-level s.e.), specular-chain light hits %ld\n", bx, by,
                    mean, std::sqrt(var), hits);
        std::fflush(stdout);
    }
}
