// Shared by path_tracer.cpp and light_tracer.cpp: the geometry of
// scenes/tungsten/volumetric-caustic (a [-1,1] x [0,2] x [-1,1] box of Lambert walls, a forward
// front wall at z = 1 with the gas inside, the glass ball, the light quad facing down) and the
// pinhole camera, in double precision. An analysis aid for docs/TESTING.md, not part of the build.
#pragma once
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstdint>
#include <vector>
#include <string>

struct V { double x, y, z; };
inline V operator+(V a, V b) { return {a.x + b.x, a.y + b.y, a.z + b.z}; }
inline V operator-(V a, V b) { return {a.x - b.x, a.y - b.y, a.z - b.z}; }
inline V operator*(V a, double s) { return {a.x * s, a.y * s, a.z * s}; }
inline V mul(V a, V b) { return {a.x * b.x, a.y * b.y, a.z * b.z}; }
inline double dot(V a, V b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
inline V cross(V a, V b) { return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x}; }
inline V norm(V a) { return a * (1.0 / std::sqrt(dot(a, a))); }
inline double maxc(V a) { return std::max(a.x, std::max(a.y, a.z)); }

struct Rng {
    uint64_t s;
    double next() {
        s ^= s << 13; s ^= s >> 7; s ^= s << 17;
        return (s >> 11) * (1.0 / 9007199254740992.0);
    }
};

enum Kind { LAMBERT, FORWARD, DIELECTRIC, LIGHT };
struct Quad { V base, e0, e1, n; Kind kind; V albedo; };
static std::vector<Quad> quads;
static const V sc = {-0.22827, 1.2, 0.152505};
static const double sr = 0.3;
static const double PI = 3.14159265358979323846;
static V Le;
static int LIGHTQ;
static double lightArea;
static bool ballGas = false;

inline void addQuad(V centre, V e0, V e1, V n, Kind k, V albedo) {
    quads.push_back({centre - e0 * 0.5 - e1 * 0.5, e0, e1, n, k, albedo});
}

struct Hit { double t; int prim; /* -1 sphere */ V p, n; };

inline bool quadHit(const Quad& q, V o, V d, double tmax, double& t) {
    double nd = dot(d, q.n);
    if (std::abs(nd) < 1e-12) return false;
    t = dot(q.base - o, q.n) / nd;
    if (!(t > 1e-6 && t < tmax)) return false;
    V v = o + d * t - q.base;
    double a = dot(v, q.e0) / dot(q.e0, q.e0), b = dot(v, q.e1) / dot(q.e1, q.e1);
    return a >= 0 && a <= 1 && b >= 0 && b <= 1;
}

inline bool intersect(V o, V d, double tmax, Hit& h) {
    h.t = tmax; h.prim = -2;
    for (size_t i = 0; i < quads.size(); ++i) {
        double t;
        if (quadHit(quads[i], o, d, h.t, t)) { h.t = t; h.prim = int(i); }
    }
    V f = o - sc;
    double b = dot(f, d), c = dot(f, f) - sr * sr, disc = b * b - c;
    if (disc > 0) {
        double s = std::sqrt(disc);
        double t0 = -b - s, t1 = -b + s;
        double t = t0 > 1e-6 ? t0 : t1;
        if (t > 1e-6 && t < h.t) { h.t = t; h.prim = -1; }
    }
    if (h.prim == -2) return false;
    h.p = o + d * h.t;
    h.n = h.prim == -1 ? norm(h.p - sc) : quads[h.prim].n;
    return true;
}

inline bool inBox(V p) { return std::abs(p.x) < 1 && p.y > 0 && p.y < 2 && std::abs(p.z) < 1; }

// medium at a point just off a surface: gas inside the box and outside the ball
inline bool gasAt(V p) {
    if (!inBox(p)) return false;
    if (!ballGas && dot(p - sc, p - sc) < sr * sr) return false;
    return true;
}

// transmittance along a shadow segment to the light (or 0 if blocked), medium by midpoint
inline double shadow(V o, V d, double dist) {
    Hit h;
    if (intersect(o, d, dist * (1 - 1e-7), h)) return 0.0;
    // segment: only gas (blocked by the ball otherwise); inside box throughout
    return gasAt(o + d * (0.5 * dist)) ? std::exp(-dist) : 1.0;
}

inline double power(double a, double b) { return a * a / (a * a + b * b); }

// light sample: returns radiance/pdf * mis-free pieces; wi, pdf
inline bool sampleLight(V p, Rng& r, V& wi, double& dist, double& pdf) {
    const Quad& L = quads[LIGHTQ];
    if (dot(L.n, p - L.base) <= 0) return false;
    V q = L.base + L.e0 * r.next() + L.e1 * r.next();
    V d = q - p;
    double r2 = dot(d, d);
    dist = std::sqrt(r2);
    wi = d * (1 / dist);
    double cosT = -dot(L.n, wi);
    pdf = r2 / (cosT * lightArea);
    return true;
}

// pdf and hit of a ray against the light alone
inline bool hitLight(V o, V d, double& t, double& pdf) {
    const Quad& L = quads[LIGHTQ];
    if (!quadHit(L, o, d, 1e30, t)) return false;
    if (dot(d, L.n) >= 0) return false;  // back side: no emission
    pdf = t * t / (std::abs(dot(L.n, d)) * lightArea);
    return true;
}

inline void frame(V n, V& t, V& b) {
    V a = std::abs(n.x) > 0.5 ? V{0, 1, 0} : V{1, 0, 0};
    t = norm(cross(a, n)); b = cross(n, t);
}


// The scene; the light's edges scaled by lightScale at the same power.
inline void buildScene(double lightScale) {
    V wall = {0.725, 0.71, 0.68};
    addQuad({0, 0, 0}, {2, 0, 0}, {0, 0, 2}, {0, 1, 0}, LAMBERT, wall);                    // floor
    addQuad({0, 2, 0}, {2, 0, 0}, {0, 0, 2}, {0, -1, 0}, LAMBERT, wall);                   // ceiling
    addQuad({0, 1, -1}, {2, 0, 0}, {0, 2, 0}, {0, 0, 1}, LAMBERT, wall);                   // back wall
    addQuad({0, 1, 1}, {2, 0, 0}, {0, 2, 0}, {0, 0, -1}, FORWARD, wall);                   // front wall
    addQuad({1, 1, 0}, {0, 2, 0}, {0, 0, 2}, {-1, 0, 0}, LAMBERT, {0.14, 0.45, 0.091});    // right wall
    addQuad({-1, 1, 0}, {0, 2, 0}, {0, 0, 2}, {1, 0, 0}, LAMBERT, {0.63, 0.065, 0.05});    // left wall
    LIGHTQ = int(quads.size());
    addQuad({-0.005, 1.98, -0.03}, {0.005 * lightScale, 0, 0}, {0, 0, 0.004 * lightScale}, {0, -1, 0}, LIGHT,
            {0, 0, 0});
    lightArea = 0.005 * 0.004 * lightScale * lightScale;
    Le = V{34, 24, 8} * (1 / (PI * lightArea));  // Tungsten: power / (pi area)
}

// Pinhole camera of the scene (fov 35 degrees horizontal); image plane at distance `plane`.
struct Camera {
    V pos = {-1.05697e-6, 1, 7};
    V fwd, right, up;
    double plane;
    Camera() {
        fwd = norm(V{0, 1, 0} - pos);
        right = norm(cross(fwd, {0, 1, 0}));
        up = cross(right, fwd);
        plane = 1 / std::tan(0.5 * 35 * PI / 180);
    }
};
