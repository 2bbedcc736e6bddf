// photon_trace: the photon paths of a round, which the subgroups take in chunks (traceLanes,
// below). A light is picked in proportion to its power, a photon leaves it with power
// Phi / (p(light) N), follows mirror and dielectric bounces, and is
// stored at every hit whose material has a non-delta lobe (Lambert and the glossy materials; when
// direct light comes from next-event estimation, only after the photon first scattered), then
// continues by sampling the BSDF with Russian roulette on its throughput.
// A photon keeps its vertex index v (1: the first surface the light reaches, specular ones counted).
// With Tungsten's max_bounces M a full path joins a photon at v to a camera chain of c vertices
// (the gather vertex counted in both) and has v + c - 1 scattering vertices, at most M - 1 (the
// path tracer's depth k = M - 1); c >= 1, so vertices beyond M - 1 are not traced.
#version 460
#extension GL_GOOGLE_include_directive : require
#extension GL_EXT_control_flow_attributes : require  // [[unroll]]: scene_geometry.glsl
#extension GL_KHR_shader_subgroup_ballot : require
#extension GL_KHR_shader_subgroup_vote : require
#extension GL_EXT_shader_explicit_arithmetic_types_int64 : require
#define TELESCOPE_INT64  // shared/sampling.h: curvePosition

#include "shared/gpu_types.h"
#include "shared/rng.h"
#include "shared/sampling.h"
#include "shared/photon_density.h"
#include "photon_scene.glsl"

layout(local_size_x = kPhotonTraceGroupSize) in;
layout(push_constant) uniform Push { PhotonTracePush pc; };

// ---- Stratified emission along a Z-order curve ----
// Path i of N takes a uniform point T of the stretch [i, i + 1) 2^32 / N of the 32-bit positions
// of a Z-order (Morton) curve through the unit square (point lights: the direction) or the unit
// 4-cube (area lights: position and direction); the curve's cell of T, jittered uniformly, gives
// the emission's random numbers (shared/sampling.h). Over the N paths of a pass the T are exactly
// uniform on [0, 2^32), so the pass's photons are a stratified sample of the emitted light: the
// estimate stays unbiased (power Phi / N each) and varies less. The point of it is order:
// consecutive paths leave in nearby directions from nearby points, so the photons a SIMD group
// stores land near each other and the hash grid's count and scatter touch nearby buckets and
// memory (docs/BENCHMARKS.photon-notes.md), where independent directions made every access random.
//
// Under Tungsten's cap (PhotonTracePush) a pass traces a number of rounds that depends on what
// the earlier rounds stored, so the rounds traced must cover the curve evenly whatever their
// number: lane l owns 2^roundBits consecutive stretches and round r takes the one at
// bitfieldReverse(r) (van der Corput's order), so every round spreads over the whole curve and the
// rounds traced fill each lane's stretches evenly; the pass shifts the curve by a uniform
// curveShift, which keeps every path's T uniform on its own (each path's photons unbiased) while
// consecutive lanes still leave side by side. (Rounds that took whole segments of the curve
// each lit the scene from a part of the light only: 4.7 times the standard deviation of the
// image, measured on the water pool.)
//
// Emission: origin, direction and power of a photon leaving a light picked by power; stratum of
// strata: the path's stretch of the curve.
void emitPhoton(uint stratum, uint strata, inout Rng rng, out vec3 origin, out vec3 dir, out vec3 power) {
    uint li = pickLight(rngNext(rng));
    LightGpu light = sceneLight(li);
    uint t = curvePosition(stratum, strata, rngNextUint(rng)) + pc.curveShift;
    float u1, u2, u3 = 0.0, u4 = 0.0;
    if (light.type == kLightPoint) {
        u1 = (float(curveCoordinate2(t, 0u)) + rngNext(rng)) * (1.0 / 65536.0);
        u2 = (float(curveCoordinate2(t, 1u)) + rngNext(rng)) * (1.0 / 65536.0);
    } else {
        u1 = (float(curveCoordinate4(t, 0u)) + rngNext(rng)) * (1.0 / 256.0);
        u2 = (float(curveCoordinate4(t, 1u)) + rngNext(rng)) * (1.0 / 256.0);
        u3 = (float(curveCoordinate4(t, 2u)) + rngNext(rng)) * (1.0 / 256.0);
        u4 = (float(curveCoordinate4(t, 3u)) + rngNext(rng)) * (1.0 / 256.0);
    }
    // (float rounding can give 1.0 in the last cell: keep every u below 1)
    const float kBelowOne = 0.99999994;
    u1 = min(u1, kBelowOne);
    u2 = min(u2, kBelowOne);
    u3 = min(u3, kBelowOne);
    u4 = min(u4, kBelowOne);
    if (light.type == kLightPoint) {
        // Intensity I: flux 4 pi I, uniform directions.
        origin = light.position;
        dir = sampleUniformSphere(u1, u2);
        power = light.radiance * (4.0 * kPi / light.pmf) * pc.pathScale;
        return;
    }
    if (light.type == kLightEnvironment || light.type == kLightCap) {
        // A light at infinity: a direction w towards it (the light sampling's own routine, pdf p(w)),
        // then a uniform point of the disk of radius R that faces w on the sphere around the
        // geometry; the photon enters along -w. Every ray from the light that can reach the
        // geometry crosses that disk once, and the flux through it is L(w) pi R^2 per unit solid
        // angle, so the photon carries L(w) pi R^2 / p(w) (the light selection's power uses the
        // same disk: render/gpu_scene.cpp).
        vec3 w, radiance = light.radiance;
        float pdf;
        if (light.type == kLightCap) {
            w = sampleUniformCone(light.position, light.cosCap, u1, u2);
            pdf = 1.0 / (2.0 * kPi * (1.0 - light.cosCap));
        } else if (kEnvironmentMap) {
            vec2 uv;
            if (!envSample(vec2(u1, u2), w, uv, pdf)) {
                origin = pc.sceneCentre;
                dir = vec3(0.0, 0.0, 1.0);
                power = vec3(0.0);  // lost (a pole of the image): nothing carried
                return;
            }
            radiance = envLookup(uv);
        } else {
            w = sampleUniformSphere(u1, u2);
            pdf = 1.0 / (4.0 * kPi);
        }
        float r = pc.sceneRadius;
        origin = sampleDisk(pc.sceneCentre + w * r, w, r, u3, u4);
        dir = -w;
        power = radiance * (kPi * r * r / (pdf * light.pmf)) * pc.pathScale;
        return;
    }
    // Area light of radiance L: flux pi A L, uniform points, cosine-distributed directions.
    Prim pr = scenePrim(light.prim);
    vec3 q, nq;
    sampleEmitterPoint(pr, kHasSpheres, kHasDisks, u1, u2, q, nq);
    dir = sampleCosineHemisphere(nq, u3, u4);
    origin = offsetRayOrigin(q, nq, dir);
    power = light.radiance * (kPi * pr.area / light.pmf) * pc.pathScale;
}

// The lanes of a subgroup that store at this vertex take consecutive slots reserved by ONE atomic on
// the shared counter, not one atomic per photon: on lavapipe the counter's cache line moves between
// the cores at every atomic; the stores were a third to a half of this pass (docs/BENCHMARKS.photon-notes.md).
// Capped passes: the subgroup whose photons reach storeCap marks the round (cappedAtRound).
void storePhoton(PhotonMapRef map, PhotonArrayRef photons, uint capacity, vec3 p, vec3 wi, vec3 power, uint vertex,
                 uint roundIndex) {
    uvec4 lanes = subgroupBallot(true);
    uint first = 0u;
    if (subgroupElect()) {
        uint n = subgroupBallotBitCount(lanes);
        first = atomicAdd(map.h.storedCount, n);
        if (first + n >= pc.storeCap) atomicMin(map.h.cappedAtRound, roundIndex);
    }
    uint slot = subgroupBroadcastFirst(first) + subgroupBallotExclusiveBitCount(lanes);
    if (slot >= capacity) return;  // counted: the host grows the buffer and repeats the pass
    photons.p[slot] = Photon(p, vertex, power, encodeDirection(wi));
}

// A photon path in flight: where its next segment starts, the power it carries, the vertex it
// reaches next, whether its light is still direct, and its random numbers.
struct PhotonPath {
    vec3 origin;
    uint vertex;
    vec3 dir;
    bool direct;
    vec3 power;
    Rng rng;
};

// Path `path` of the pass from the curve's stretch `stratum` of `strata`: false if it carries nothing.
bool startPhotonPath(uint path, uint stratum, uint strata, out PhotonPath ph) {
    uint seed = pc.seed ^ 0x5bd1e995u;
    if (pc.passInBlock != 0u) seed ^= pcgHash(pc.passInBlock);  // the passes of a block differ
    ph.rng = rngCreate(path, pc.pass, seed);
    emitPhoton(stratum, strata, ph.rng, ph.origin, ph.dir, ph.power);
    // Direct light until the photon scatters: straight passes (transparency, a thin sheet's
    // transmission) keep it direct, since next-event shadow rays pass those surfaces too.
    ph.direct = true;
    ph.vertex = 1u;
    return any(greaterThan(ph.power, vec3(0.0))) && ph.vertex + 1u <= kPhotonMaxBounces;
}

// One segment of the path (in round roundIndex): the hit, the photon stored there, the bounce.
// False when the path ends.
bool photonStep(PhotonMapRef map, PhotonArrayRef photons, uint capacity, uint roundIndex, inout PhotonPath ph) {
    Hit hit;
    if (!traceClosest(ph.origin, ph.dir, kInfinity, hit)) return false;
    vec3 dir = ph.dir;
    Prim pr = scenePrim(hit.prim);
    vec3 p, ng;
    hitPoint(pr, ph.origin, dir, hit.t, p, ng);
    MaterialGpu m = sceneMaterial(pr.material);
    vec3 ns = shadingNormal(hit.prim, hit.bary, ng);  // ng unless the triangle is smooth-shaded
    bool front = dot(dir, ns) < 0.0;
    vec3 n = front ? ns : -ns;  // faces the incoming photon

    // ---- Store where the material has a non-delta lobe ----
    // (A mixture's photon is stored before it picks the component it scatters by: the incident
    // flux does not depend on that choice, and a gather there draws its own component.)
    // A rough dielectric (or a composite with one: kMaterialBothSides) keeps photons on both
    // sides: its gather transmits those from the far side.
    bool nonDelta = m.type == kBsdfLambert ||
                    (kBsdfFamilies != 0u && (isGlossyBsdf(m.type) || m.type == kBsdfMixed || m.type == kBsdfTransparency));
    bool bothSides = (kBsdfFamilies & kFamilyRoughDielectric) != 0u && (m.flags & kMaterialBothSides) != 0u;
    if (nonDelta && (front || kTwoSided || bothSides) && (!kNextEvent || !ph.direct))
        storePhoton(map, photons, capacity, p, -dir, ph.power, ph.vertex, roundIndex);

    // ---- Scatter ----
    if (kHasTextures) applyTextures(m, pr, hit.prim, hit.bary, p);
    vec3 scale = vec3(1.0);
    uint index = pr.material;
    // mixed: one component; transparency: its base, or straight on (pass)
    bool pass = kBsdfFamilies != 0u && resolveComposite(m, index, scale, pr, hit.prim, hit.bary, p, ph.rng);
    bool straight = pass;
    if (pass) {
        // straight on: a bounce with the direction unchanged
    } else if ((kBsdfFamilies & kFamilyThinSheet) != 0u && m.type == kBsdfThinSheet) {
        // specular reflection or straight on (shared/bsdf.h thinSheetScatter)
        vec3 weight;
        if (thinSheetScatter(m, abs(dot(dir, ng)), rngNext(ph.rng), weight)) dir = reflect(dir, n);
        else straight = true;
        scale *= weight;
    } else if (m.type == kBsdfLambert) {
        if (!front && !kTwoSided) return false;
        dir = sampleCosineHemisphere(n, rngNext(ph.rng), rngNext(ph.rng));
        if (dot(dir, n) <= 0.0) return false;
        scale *= m.albedo;
    } else if (kHasSpecular && isSpecularBsdf(m.type)) {
        scale *= scatterSpecular(m, front, n, dir, ph.rng);
    } else if (kBsdfFamilies != 0u && isGlossyBsdf(m.type)) {
        // A photon samples the glossy materials as a camera path does, with wi towards where it
        // came from: the weight eval(wi, wo) / pdf is f(wi -> wo) |cos wo| / pdf, the flux it
        // carries on towards wo. The reflecting materials are reciprocal (tests/unit/
        // glossy_bsdf_test.cpp); the rough dielectric's refraction is not, and its eval carries
        // the eta^2 of wo's side, which is f for light travelling from wi to wo (shared/bsdf.h
        // roughRefractionRadianceScale). A rough dielectric keeps its outward frame, as in the
        // path tracer (wi.z < 0 inside).
        bool dielectric = (kBsdfFamilies & kFamilyRoughDielectric) != 0u && m.type == kBsdfRoughDielectric;
        if (!front && !kTwoSided && !dielectric) return false;
        vec3 nf = dielectric ? ns : n;
        vec3 t, b;
        buildFrame(nf, t, b);
        vec3 wi = vec3(dot(-dir, t), dot(-dir, b), dot(-dir, nf));
        vec3 wo, weight;
        float pdf;
        bool dirac;
        if (!glossySample(m, wi, ph.rng, wo, weight, pdf, dirac)) return false;
        dir = normalize(t * wo.x + b * wo.y + nf * wo.z);
        scale *= weight;
    } else {
        return false;  // null: black and opaque
    }

    // ---- Russian roulette on the throughput factor of this vertex ----
    float q = min(maxComponent(scale), 1.0);
    if (!(q > 0.0)) return false;
    if (q < 1.0 && rngNext(ph.rng) >= q) return false;
    ph.power *= scale / q;
    ph.dir = dir;
    ph.origin = offsetRayOrigin(p, ng, dir);
    ph.direct = ph.direct && straight;
    ++ph.vertex;
    return ph.vertex + 1u <= kPhotonMaxBounces;
}

#include "loop_cap.glsl"

// The paths of this dispatch's round (PhotonTracePush), with path regeneration: the lanes of a
// subgroup take the round's lanes in chunks of a subgroup's width of consecutive ones (one atomic
// on the round's roundTaken per chunk) and a lane whose path ended starts the next lane of the chunk, so
// that the SIMD group's segment loop keeps its lanes busy. (One path a thread left 40% of the
// lanes idle on the water caustic: a group ran until its longest path ended; docs/BENCHMARKS.md.)
// A subgroup takes chunks until it has run kTraceSegmentBudget segment iterations: the walks of
// those segments count towards lavapipe's loop cap like the path tracer's loop budget
// (kSafeLoopBudget: 64 walks of kRayLoopTicks). The dispatch has a thread for every lane and
// each subgroup takes at least one chunk, so every chunk of the round is traced; the subgroups
// that come after the round is taken end at once. Consecutive lanes leave nearby on the
// emission curve, so a chunk's paths stay coherent.
// Lane l of round r is path r * laneCount + l (below pathCount); it is counted in the header's
// tracedPaths. Capped: the round is traced only if no earlier round filled the budget
// (cappedAtRound, final once the earlier dispatches are done: the round's own stores only write
// values equal to its index).
const uint kTraceSegmentBudget = kSafeLoopBudget / kRayLoopTicks;  // 64

void traceLanes() {
    if (kLightCount == 0u) return;
    PhotonMapRef map = PhotonMapRef(uvec2(pc.headerLo, pc.headerHi));
    bool capped = pc.storeCap != 0xffffffffu;
    if (capped && map.h.cappedAtRound < pc.roundIndex) return;
    uint laneEnd = min(pc.laneCount, pc.pathCount - min(pc.pathCount, pc.roundIndex * pc.laneCount));
    if (map.h.roundTaken[pc.roundIndex] >= laneEnd) return;  // the round is taken (the counter only grows)
    PhotonArrayRef photons = PhotonArrayRef(uvec2(map.h.photonsLo, map.h.photonsHi));
    uint capacity = map.h.capacity;
    uint place = pc.roundBits == 0u ? 0u : bitfieldReverse(pc.roundIndex) >> (32u - pc.roundBits);

    uint chunk = gl_SubgroupSize;
    PhotonPath ph;
    bool alive = false;
    uint chunkNext = 0u, chunkEnd = 0u;  // subgroup-uniform: the lanes of the chunk not yet started
    bool taking = true;                  // subgroup-uniform: more chunks may be taken
    uint started = 0u;                   // subgroup-uniform: paths started
    // Each iteration starts a path or runs a segment of a live one; a subgroup takes chunks for
    // kTraceSegmentBudget iterations and then finishes its live paths and its last chunk's, at most
    // 2 chunk paths of at most kPhotonMaxBounces - 1 segments each, so the loop never ends by its bound.
    uint iterations = kTraceSegmentBudget + 2u * chunk * kPhotonMaxBounces;
    for (uint it = 0u; it < iterations; ++it) {
        if (chunkNext == chunkEnd && taking && subgroupAny(!alive)) {
            uint first = 0u;
            if (subgroupElect()) first = atomicAdd(map.h.roundTaken[pc.roundIndex], chunk);
            first = subgroupBroadcastFirst(first);
            chunkNext = min(first, laneEnd);
            chunkEnd = min(first + chunk, laneEnd);
            taking = chunkNext < chunkEnd && it < kTraceSegmentBudget;
        }
        // idle lanes start the chunk's next lanes, in lane order
        uvec4 idle = subgroupBallot(!alive);
        uint rank = subgroupBallotExclusiveBitCount(idle);
        uint starts = min(subgroupBallotBitCount(idle), chunkEnd - chunkNext);
        if (!alive && rank < starts) {
            uint lane = chunkNext + rank;
            uint path = pc.roundIndex * pc.laneCount + lane;
            uint stratum = capped ? (lane << pc.roundBits) + place : path;
            uint strata = capped ? pc.laneCount << pc.roundBits : pc.pathCount;
            alive = startPhotonPath(path, stratum, strata, ph);
        }
        chunkNext += starts;
        started += starts;
        if (!subgroupAny(alive)) {
            if (chunkNext == chunkEnd && !taking) break;
            continue;
        }
        if (alive) alive = photonStep(map, photons, capacity, pc.roundIndex, ph);
    }
    if (subgroupElect() && started != 0u) atomicAdd(map.h.tracedPaths, started);
}

void main() {
    traceLanes();
    // lanes whose loops lavapipe's cap may have ended: the host reports them (an error)
    if (loopCapReached(2u + (pc.pathCount >> 31u)))
        atomicAdd(PhotonMapRef(uvec2(pc.headerLo, pc.headerHi)).h.loopCapHits, 1u);
}
