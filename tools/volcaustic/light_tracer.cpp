// A light tracer for the caustic of scenes/tungsten/volumetric-caustic: N particles from the
// light (uniform point, cosine direction, power 66 in R + G + B), weighted by the transmittance
// to the ball (no scattering before it: what scatters before the ball is light that a path
// tracer's light sampling finds), through the ball (Fresnel reflection or refraction, ior 1.5,
// vacuum inside), then to the first scattering point in the gas or the first Lambert surface,
// which is connected to the pinhole: radiance phase (or albedo / pi |cos|) T / (r^2 Omega_pixel)
// into the pixel it projects to. That is the caustic with one diffuse vertex after the ball, the
// part a path tracer finds only by hitting the light through the ball. Prints it summed over the
// image and per block (16 x 16-pixel block means of the 256 x 144 image; MAP=1: all blocks).
//   built by CMake (volcaustic_light_tracer; tests/volcaustic_check.py reruns it), or
//   g++ -O2 -o light_tracer light_tracer.cpp && ./light_tracer 2000000
#include "scene.h"

int main(int argc, char** argv) {
    long N = argc > 1 ? std::atol(argv[1]) : 2000000;  // particles
    double IOR = getenv("IOR") ? std::atof(getenv("IOR")) : 1.5;
    buildScene(1.0);
    const int W = 256, H = 144;
    const Camera c;
    const V cam = c.pos, fwd = c.fwd, right = c.right, up = c.up;
    const double plane = c.plane;
    double wpx = 2.0 / (plane * W);
    std::vector<double> img(W * H, 0.0), imgF(W * H, 0.0);
    Rng r{12345};
    const Quad& Lq = quads[LIGHTQ];
    double Psum = 66.0;
    auto connect = [&](V x, double f, std::vector<double>& out) {
        V d = x - cam;
        double z = dot(d, fwd);
        if (z <= 0) return;
        double fx = (plane * dot(d, right) / z + 1) * 0.5 * W, fy = (double(H) / W - plane * dot(d, up) / z) * 0.5 * W;
        int ix = int(std::floor(fx)), iy = int(std::floor(fy));
        if (ix < 0 || iy < 0 || ix >= W || iy >= H) return;
        double r2 = dot(d, d), dist = std::sqrt(r2);
        V u = (cam - x) * (1 / dist);
        // visibility: anything between x and the front wall blocks (the front wall is forward)
        Hit h;
        double tWall = (1.0 - x.z) / u.z;  // distance to z = 1
        if (intersect(x, u, tWall * (1 - 1e-9), h)) return;
        double T = std::exp(-tWall);
        double cosT = z / dist;
        double omega = wpx * wpx * cosT * cosT * cosT;
        out[iy * W + ix] += f * T / (r2 * omega);
    };
    for (long i = 0; i < N; ++i) {
        V o = Lq.base + Lq.e0 * r.next() + Lq.e1 * r.next();
        double u1 = r.next(), u2 = r.next();
        double rr = std::sqrt(u1), ph = 2 * PI * u2;
        V d = V{rr * std::cos(ph), -std::sqrt(std::max(0.0, 1 - u1)), rr * std::sin(ph)};
        double w = Psum / N;
        // fly to the ball without scattering
        Hit h;
        if (!intersect(o, d, 1e30, h) || h.prim != -1) continue;
        w *= std::exp(-h.t);  // probability of no scattering before the ball (weight instead of sampling)
        // through the ball: specular chain, until the ray leaves it
        bool inside = false;
        int guard = 0;
        for (; guard < 20; ++guard) {
            bool front = dot(d, h.n) < 0;
            V n = front ? h.n : h.n * -1;
            double eta = front ? 1 / IOR : IOR, cosI = -dot(d, n), sin2T = eta * eta * (1 - cosI * cosI), F = 1, cosT = 0;
            if (sin2T < 1) {
                cosT = std::sqrt(1 - sin2T);
                double rs = (eta * cosI - cosT) / (eta * cosI + cosT), rp = (cosI - eta * cosT) / (cosI + eta * cosT);
                F = 0.5 * (rs * rs + rp * rp);
            }
            if (r.next() < F) d = d + n * (2 * cosI);
            else { d = norm(d * eta + n * (eta * cosI - cosT)); inside = front; }
            o = h.p;
            if (!inside) break;
            if (!intersect(o, d, 1e30, h) || h.prim != -1) { guard = 99; break; }
        }
        if (guard >= 20 || inside) continue;
        if (!intersect(o, d, 1e30, h)) continue;
        if (h.prim == -1) continue;  // reflected back into the ball from outside: ignore (rare)
        double t = -std::log(1 - r.next());
        if (t < h.t) {
            connect(o + d * t, w / (4 * PI), img);  // weight: sigma_s = 1, sampled exactly
        } else if (quads[h.prim].kind == LAMBERT) {
            const Quad& q = quads[h.prim];
            V x = h.p;
            V toCam = norm(cam - x);
            double c = std::abs(dot(toCam, q.n));
            double alb = (q.albedo.x * 34 + q.albedo.y * 24 + q.albedo.z * 8) / 66;
            connect(x + q.n * (dot(toCam, q.n) > 0 ? 1e-7 : -1e-7), w * alb / PI * c, imgF);
        }
    }
    if (getenv("MAP")) {
        for (int by = 0; by < 9; ++by) {
            for (int bx = 0; bx < 16; ++bx) {
                double sm = 0;
                for (int y = by * 16; y < by * 16 + 16; ++y)
                    for (int x = bx * 16; x < bx * 16 + 16; ++x) sm += img[y * W + x] + imgF[y * W + x];
                std::printf("%6.3f ", sm / 256);
            }
            std::printf("\n");
        }
    }
    int blocks[][2] = {{6, 4}, {6, 5}, {5, 6}, {6, 7}, {4, 8}, {4, 7}, {7, 2}, {5, 8}, {5, 7}, {7, 4}, {7, 5}, {5, 5}};
    double tm = 0, tf = 0;
    for (int k = 0; k < W * H; ++k) { tm += img[k]; tf += imgF[k]; }
    std::printf("image sum / 256: medium caustic %.3f, surface caustic %.3f\n", tm / 256, tf / 256);
    for (auto& b : blocks) {
        double sm = 0, sf = 0;
        for (int y = b[1] * 16; y < b[1] * 16 + 16; ++y)
            for (int x = b[0] * 16; x < b[0] * 16 + 16; ++x) { sm += img[y * W + x]; sf += imgF[y * W + x]; }
        std::printf("block %d,%d: caustic (medium %.3f + surface %.3f) = %.3f\n", b[0], b[1], sm / 256, sf / 256, (sm + sf) / 256);
    }
}
