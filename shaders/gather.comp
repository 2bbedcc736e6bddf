// gather: one thread per pixel and photon pass. The camera path follows mirror and dielectric
// bounces (and plastic's coat, by a lobe choice) to the first vertex with a non-delta lobe, where
// the photon map gives, each photon weighted by the BSDF (Lambert or glossy: shared/bsdf.h),
//   biased:   the pass's sample  K_r                     (fixed radius or the PPM pass radius)
//   unbiased: the pass's part of a block of m^k passes at level k (docs/PHOTON-MAPPING.md):
//             Z = mean over the block of [K_{r_b} + (K_{r_{k+1}} - K_{r_k}) / p(k)]
// plus emission seen along the specular chain and, with direct_lighting = next_event, one light
// sample (no MIS: photons carry no direct light then). A block's sums live in the per-pixel block
// buffer until its last pass adds the sample to the film. The level is the host's (uniform
// schedule) or drawn here when a pixel starts a block (per_pixel schedule).
// A pass whose fullest bucket holds more than kGatherSlicePhotons photons runs in slices (one
// dispatch each, see photon_gather.glsl); the last slice completes the pass.
#version 460
#extension GL_GOOGLE_include_directive : require
#extension GL_EXT_control_flow_attributes : require  // [[unroll]]: photon_gather.glsl, scene_geometry.glsl

#include "shared/gpu_types.h"
#include "shared/rng.h"
#include "shared/camera.h"
#include "shared/photon_density.h"
#include "photon_scene.glsl"
layout(binding = kBindingSortedTexels) uniform usamplerBuffer sortedTexels;

// The glossy BSDF of the gather vertex being summed (gGlossy: set by sliceKernelSums), in the
// frame (t, b, n) around the normal facing the camera chain, wi towards the chain (local): each
// photon's factor f(wi, wo) = eval / |cos wo| (the photon's flux carries the cosine). A rough
// dielectric keeps its outward normal (wi.z < 0 inside) and takes photons from both sides
// (bothSides), those from the far side refracted with their radiance scaling (shared/bsdf.h
// roughRefractionRadianceScale; off with the camera side's scaling in the test's control).
// Lambertian vertices keep f outside the sums; scenes without glossy materials fold all of it away.
struct GlossyVertex {
    bool on;
    bool bothSides;
    MaterialGpu m;
    vec3 t, b, n, wi;
};
GlossyVertex gGlossy;

vec3 photonBsdf(vec3 w) {
    if (kBsdfFamilies == 0u || !gGlossy.on) return vec3(1.0);
    vec3 wo = vec3(dot(w, gGlossy.t), dot(w, gGlossy.b), dot(w, gGlossy.n));
    if (!(wo.z > 0.0) && !(gGlossy.bothSides && wo.z < 0.0)) return vec3(0.0);
    vec3 f = glossyEval(gGlossy.m, gGlossy.wi, wo);
    if (gGlossy.bothSides && kRadianceScaling) f *= roughRefractionRadianceScale(gGlossy.m.ior, gGlossy.wi, wo);
    return kTestCosine ? f : f / abs(wo.z);
}
#define PHOTON_BSDF(w) photonBsdf(w)
#define PHOTON_BOTH_SIDES ((kBsdfFamilies & kFamilyRoughDielectric) != 0u && gGlossy.bothSides)
#include "photon_gather.glsl"
#include "accumulate.glsl"

layout(local_size_x = kGatherGroupSize, local_size_y = kGatherGroupSize) in;

layout(push_constant) uniform Push { GatherPush pc; };

// Next-event estimation at the gather vertex: one light picked by power (scene_common.glsl), one
// shadow ray, f = the Lambert albedo / pi (glossy false) or the glossy BSDF in the frame (t, b, n)
// for wi (local). No MIS: the camera chain stops at this vertex, so no BSDF sample could find the
// light.
// The shadow ray passes thin sheets and transparency; a sample that crosses more than maxCrossings
// of them has more scattering vertices than max_bounces allows.
vec3 directLight(vec3 p, vec3 ng, vec3 n, vec3 albedo, bool glossy, MaterialGpu m, vec3 t, vec3 b, vec3 wi,
                 uint maxCrossings, inout Rng rng) {
    LightSample ls;
    if (!sampleLight(p, rng, ls)) return vec3(0.0);
    float cosS = dot(n, ls.wi);
    // a rough dielectric (outward n) also takes light from behind, refracted as a photon would be
    bool dielectric = (kBsdfFamilies & kFamilyRoughDielectric) != 0u && glossy && m.type == kBsdfRoughDielectric;
    if (!(cosS > 0.0) && !(dielectric && cosS < 0.0)) return vec3(0.0);
    vec3 value = ls.weight * cosS;
    if (kBsdfFamilies != 0u && glossy) {
        vec3 wo = vec3(dot(ls.wi, t), dot(ls.wi, b), cosS);
        value = ls.weight * glossyEval(m, wi, wo);
        if (dielectric && kRadianceScaling) value *= roughRefractionRadianceScale(m.ior, wi, wo);
    }
    if (!any(greaterThan(value, vec3(0.0)))) return vec3(0.0);
    vec3 o = offsetRayOrigin(p, ng, ls.wi);
    float tMax = ls.dist < kInfinity ? max(ls.dist - length(o - p), 0.0) : kInfinity;
    uint crossings;
    value *= surfaceShadow(o, ls.wi, tMax, rng, crossings);
    if (crossings > maxCrossings) return vec3(0.0);
    if (kBsdfFamilies != 0u && glossy) return value;
    return albedo * kInvPi * value;
}

// The per-pixel block buffer (kGatherBlockVec4s vec4 per pixel): compensated sums of the block's
// base and correction (hi, lo pairs; w of the first: level + 1 for per_pixel, 0 = no block; w of
// the second: passes done), the kernel sums of the slices before the last, and the gather vertex
// the first slice found.
const uint kBlockBaseHi = 0u, kBlockBaseLo = 1u, kBlockCorrHi = 2u, kBlockCorrLo = 3u;
const uint kSliceBase = 4u, kSliceDifference = 5u;
const uint kBlockVertex = 6u;  // 6 vec4: the gather vertex of a pass in slices (storeGatherVertex)
// k-nearest gathers: the k nearest photons follow (photon_gather.glsl, nearestStore).
const uint kBlockStride = kGatherBlockVec4s + (kGatherCount + 1u) / 2u;

// The camera chain's gather vertex: where it reached a surface with a non-delta lobe (vertex v > 0;
// 0 when the chain ended without one), the normal facing the chain, the light it saw (emission
// along the chain and, with next-event estimation, one light sample there) and its BSDF: at a
// Lambertian vertex (material kNoGlossy) f = throughput x albedo / pi; at a glossy one f = the
// throughput (over 1 - p of a Dirac lobe not taken), the material (index, and the values its
// textures gave) and wi, the direction towards the chain.
const uint kNoGlossy = 0xffffffffu;
struct GatherVertex {
    vec3 p;
    vec3 n;
    vec3 f;
    vec3 light;
    uint vertex;
    uint material;
    vec3 wi;
    vec3 albedo;
    float roughness;
    float substrateWeight;
};

GatherVertex traceCameraChain(vec3 origin, vec3 dir, inout Rng rng) {
    GatherVertex gv;
    gv.p = vec3(0.0);
    gv.n = vec3(0.0);
    gv.f = vec3(0.0);
    gv.light = vec3(0.0);
    gv.vertex = 0u;
    gv.material = kNoGlossy;
    gv.wi = vec3(0.0);
    gv.albedo = vec3(0.0);
    gv.roughness = 0.0;
    gv.substrateWeight = 0.0;
    vec3 throughput = vec3(1.0);
    // The camera chain's vertex v: emission seen there has v - 1 scattering vertices, a gather or
    // light sample at v joins paths of at least v (photon_trace.comp: at most max_bounces - 1).
    for (uint v = 1u; v <= kPhotonMaxBounces; ++v) {
        Hit hit;
        if (!traceClosest(origin, dir, kInfinity, hit)) {
            // Lights at infinity seen from the camera or through delta bounces (no MIS: the chain's
            // scattering so far is all delta).
            if (kEnvironmentLight != 0xffffffffu) gv.light += throughput * environmentRadiance(sceneLight(kEnvironmentLight), dir);
            if (kCapLight != 0xffffffffu && dot(dir, sceneLight(kCapLight).position) >= sceneLight(kCapLight).cosCap)
                gv.light += throughput * sceneLight(kCapLight).radiance;
            break;
        }
        Prim pr = scenePrim(hit.prim);
        vec3 p, ng;
        hitPoint(pr, origin, dir, hit.t, p, ng);
        gv.light += throughput * primEmission(pr, dir, ng);
        if (v + 1u > kPhotonMaxBounces) break;
        MaterialGpu m = sceneMaterial(pr.material);
        if (kHasTextures) applyTextures(m, pr, hit.prim, hit.bary, p);
        uint index = pr.material;
        // mixed: one component; transparency: its base, or straight on (pass)
        bool pass = kBsdfFamilies != 0u && resolveComposite(m, index, throughput, pr, hit.prim, hit.bary, p, rng);
        vec3 ns = shadingNormal(hit.prim, hit.bary, ng);  // ng unless the triangle is smooth-shaded
        bool front = dot(dir, ns) < 0.0;
        vec3 n = front ? ns : -ns;  // faces the camera path
        uint maxCrossings = kPhotonMaxBounces - 1u - v;  // for a light sample at this vertex
        bool sheet = !pass && (kBsdfFamilies & kFamilyThinSheet) != 0u && m.type == kBsdfThinSheet;
        if (pass || sheet) {
            // straight on, or a thin sheet's specular reflection or straight pass (thinSheetScatter)
            vec3 weight = vec3(1.0);
            if (sheet && thinSheetScatter(m, abs(dot(dir, ng)), rngNext(rng), weight)) dir = reflect(dir, n);
            throughput *= weight;
            origin = offsetRayOrigin(p, ng, dir);
            continue;
        }

        if (m.type == kBsdfLambert) {
            if (!front && !kTwoSided) break;
            if (kNextEvent && kLightCount > 0u)
                gv.light += throughput * directLight(p, ng, n, m.albedo, false, m, n, n, n, maxCrossings, rng);
            gv.p = p;
            gv.n = n;
            gv.f = throughput * m.albedo * kInvPi;
            gv.vertex = v;
            break;
        }
        if (kBsdfFamilies != 0u && isGlossyBsdf(m.type)) {
            // a rough dielectric: seen from either side, in its outward frame (as in the path tracer)
            bool dielectric = (kBsdfFamilies & kFamilyRoughDielectric) != 0u && m.type == kBsdfRoughDielectric;
            if (!front && !kTwoSided && !dielectric) break;
            if (dielectric) n = ns;
            vec3 t, b;
            buildFrame(n, t, b);
            vec3 wi = vec3(dot(-dir, t), dot(-dir, b), dot(-dir, n));
            // A Dirac lobe (plastic's coat) is followed with the probability the BSDF's sampling
            // gives it; the gather then stands for the other lobes (shared/bsdf.h).
            float pDirac = glossyDiracProbability(m, wi);
            if (pDirac > 0.0 && rngNext(rng) < pDirac) {
                throughput *= glossyDiracReflectance(m, wi) / pDirac;
                dir = reflect(dir, n);
                origin = offsetRayOrigin(p, ng, dir);
                continue;
            }
            throughput /= 1.0 - pDirac;
            if (kNextEvent && kLightCount > 0u)
                gv.light += throughput * directLight(p, ng, n, m.albedo, true, m, t, b, wi, maxCrossings, rng);
            gv.p = p;
            gv.n = n;
            gv.f = throughput;
            gv.vertex = v;
            gv.material = index;
            gv.wi = -dir;
            gv.albedo = m.albedo;
            gv.roughness = m.roughness;
            gv.substrateWeight = m.substrateWeight;
            break;
        }
        if (!kHasSpecular || !isSpecularBsdf(m.type)) break;  // null
        throughput *= scatterSpecular(m, front, n, dir, rng);
        // Radiance, not flux, flows along the camera chain: refraction scales it (shared/bsdf.h).
        if (kRadianceScaling && m.type == kBsdfDielectric && dot(dir, n) < 0.0)
            throughput *= refractionRadianceScale(m, front);
        origin = offsetRayOrigin(p, ng, dir);
    }
    return gv;
}

void storeGatherVertex(AccumRef block, uint at, GatherVertex gv) {
    block.v[at] = vec4(gv.p, uintBitsToFloat(gv.vertex));
    block.v[at + 1u] = vec4(gv.n, uintBitsToFloat(gv.material));
    block.v[at + 2u] = vec4(gv.f, gv.substrateWeight);
    block.v[at + 3u] = vec4(gv.light, 0.0);
    if (kBsdfFamilies != 0u) {
        block.v[at + 4u] = vec4(gv.albedo, gv.roughness);
        block.v[at + 5u] = vec4(gv.wi, 0.0);
    }
}

GatherVertex loadGatherVertex(AccumRef block, uint at) {
    GatherVertex gv;
    vec4 a = block.v[at], n = block.v[at + 1u], f = block.v[at + 2u];
    gv.p = a.xyz;
    gv.vertex = floatBitsToUint(a.w);
    gv.n = n.xyz;
    gv.material = floatBitsToUint(n.w);
    gv.f = f.xyz;
    gv.substrateWeight = f.w;
    gv.light = block.v[at + 3u].xyz;
    gv.albedo = vec3(0.0);
    gv.roughness = 0.0;
    gv.wi = vec3(0.0);
    if (kBsdfFamilies != 0u) {
        vec4 g = block.v[at + 4u];
        gv.albedo = g.xyz;
        gv.roughness = g.w;
        gv.wi = block.v[at + 5u].xyz;
    }
    return gv;
}

// The glossy BSDF of a gather vertex for photonBsdf (off at a Lambertian one).
void setGlossyVertex(GatherVertex gv) {
    gGlossy.on = false;
    gGlossy.bothSides = false;
    if (kBsdfFamilies == 0u || gv.material == kNoGlossy) return;
    gGlossy.on = true;
    gGlossy.m = sceneMaterial(gv.material);
    gGlossy.bothSides = (kBsdfFamilies & kFamilyRoughDielectric) != 0u && gGlossy.m.type == kBsdfRoughDielectric;
    gGlossy.m.albedo = gv.albedo;
    gGlossy.m.roughness = gv.roughness;
    gGlossy.m.substrateWeight = gv.substrateWeight;
    gGlossy.n = gv.n;
    buildFrame(gv.n, gGlossy.t, gGlossy.b);
    gGlossy.wi = vec3(dot(gv.wi, gGlossy.t), dot(gv.wi, gGlossy.b), dot(gv.wi, gGlossy.n));
}

uint passSeed(uint seed, uint passInBlock) { return passInBlock == 0u ? seed : seed ^ pcgHash(passInBlock); }

// The kernel sums of this slice at the gather vertex, times its f (base at r_b, difference
// K_{r_{k+1}} - K_{r_k}); more: whether a later slice has photons for this vertex. k-nearest
// gathers carry the nearest photons so far across the slices in the block buffer and sum them in
// the vertex's last slice.
void sliceKernelSums(PhotonMapRef map, uint bi, GatherVertex gv, bool unbiased, PhotonLevels levels, uint level,
                     out vec3 kernelBase, out vec3 kernelDifference, out bool more) {
    kernelBase = vec3(0.0);
    kernelDifference = vec3(0.0);
    more = false;
    if (gv.vertex == 0u) return;
    setGlossyVertex(gv);
    float rb2 = pc.radius * pc.radius;
    GatherSums sums;
    if (kGatherCount > 0u) {
        NearestStateRef state = NearestStateRef(uvec2(pc.blockLo, pc.blockHi));
        NearestPhotons nearest;
        if (pc.slice == 0u) nearestClear(nearest);
        else nearestLoad(state, bi + kGatherBlockVec4s, nearest);
        nearestSearch(map, gv.p, rb2, pc.slice * kGatherSliceLength, nearest, more);
        if (more) {
            nearestStore(state, bi + kGatherBlockVec4s, nearest);
            return;
        }
        sums = nearestSums(map, nearest, gv.n, rb2, kKernel, kPhotonMaxBounces - gv.vertex);
    } else {
        float logRadius2 = unbiased ? photonLevelLogRadius2(levels, level) : 0.0;
        sums = gatherPhotons(map, gv.p, gv.n, rb2, unbiased, logRadius2, pc.logAreaRatio, kKernel,
                             pc.slice * kGatherSliceLength, kPhotonMaxBounces - gv.vertex, more);
    }
    kernelBase = gv.f * sums.base;
    kernelDifference = gv.f * sums.difference;
}

// Unbiased photon mapping: adds this pass's base and correction to the pixel's block. Returns
// false while the block has passes to go; true with the block's sample (the mean of its passes)
// in base and correction when this pass completes it.
bool completeBlock(AccumRef block, uint bi, PhotonLevels levels, uint level, uint done, inout vec3 base,
                   out vec3 correction, vec3 kernelDifference) {
    vec3 passCorrection = kernelDifference / photonLevelProbability(levels, level);
    if (done == 0u) {
        block.v[bi + kBlockBaseHi] = vec4(0.0);
        block.v[bi + kBlockBaseLo] = vec4(0.0);
        block.v[bi + kBlockCorrHi] = vec4(0.0);
        block.v[bi + kBlockCorrLo] = vec4(0.0);
    }
    addCompensated(block, bi + kBlockBaseHi, vec4(base, 0.0));  // w (block state) unchanged
    addCompensated(block, bi + kBlockCorrHi, vec4(passCorrection, 0.0));
    uint passes = photonBlockPasses(levels, level);
    correction = vec3(0.0);
    if (done + 1u < passes) {
        block.v[bi + kBlockBaseHi].w = float(level + 1u);
        block.v[bi + kBlockBaseLo].w = float(done + 1u);
        return false;
    }
    float inv = 1.0 / float(passes);
    base = (block.v[bi + kBlockBaseHi].xyz + block.v[bi + kBlockBaseLo].xyz) * inv;
    correction = (block.v[bi + kBlockCorrHi].xyz + block.v[bi + kBlockCorrLo].xyz) * inv;
    block.v[bi + kBlockBaseHi].w = 0.0;
    return true;
}

void gatherPixel() {
    uvec2 pixel = gl_GlobalInvocationID.xy;
    if (pixel.x >= pc.width || pixel.y >= pc.height) return;
    PhotonMapRef map = PhotonMapRef(uvec2(pc.headerLo, pc.headerHi));
    if (map.h.storedCount > map.h.capacity) return;  // photons were dropped: the host repeats the pass
    if (map.h.maxBucket > pc.sliceCount * kGatherSliceLength) return;  // too few slices: repeated too
    uint pixelIndex = pixel.y * pc.width + pixel.x;
    AccumRef block = AccumRef(uvec2(pc.blockLo, pc.blockHi));
    uint bi = pixelIndex * kBlockStride;
    // A pass in slices: a pixel whose photons an earlier slice finished is done (below)
    if (pc.slice > 0u && block.v[bi + kSliceBase].w != 0.0) return;

    // ---- Camera ray and the level of this pass ----
    Rng rng = rngCreate(pixelIndex, pc.pass, passSeed(pc.seed, pc.passInBlock));
    float u1 = rngNext(rng), u2 = rngNext(rng);
    float filterWeight;  // 1: photon mapping takes dirac, box and tent only (the loader says so)
    vec2 film = cameraFilmPoint(kFilter, pixel, vec2(u1, u2), filterWeight);
    vec3 dir = cameraRayDirection(film, pc.width, pc.height, pc.planeDistance, pc.cameraRight, pc.cameraUp,
                                  pc.cameraForward);
    const bool unbiased = kEstimator == kPhotonUnbiased;
    PhotonLevels levels = PhotonLevels(pc.pmfR, pc.logAreaRatio, pc.photonGrowth, pc.levelCap);
    float uLevel1 = rngNext(rng), uLevel2 = rngNext(rng);
    uint level = pc.level;
    uint done = pc.passInBlock;
    if (unbiased && kSchedule == kLevelSchedulePerPixel) {
        float state = block.v[bi + kBlockBaseHi].w;
        done = state == 0.0 ? 0u : uint(block.v[bi + kBlockBaseLo].w);
        level = state == 0.0 ? photonLevelSample(levels, uLevel1, uLevel2) : uint(state) - 1u;
    }

    // ---- The gather vertex: a pass in slices traces the chain in its first slice only ----
    GatherVertex gv;
    if (pc.slice == 0u) {
        gv = traceCameraChain(pc.cameraPosition, dir, rng);
        if (pc.sliceCount > 1u) storeGatherVertex(block, bi + kBlockVertex, gv);
    } else {
        gv = loadGatherVertex(block, bi + kBlockVertex);
    }
    vec3 kernelBase, kernelDifference;
    bool more;
    sliceKernelSums(map, bi, gv, unbiased, levels, level, kernelBase, kernelDifference, more);

    // ---- Slices: the kernel sums of the earlier slices wait in the block buffer. A pixel
    // completes its pass in the first slice after which its buckets hold no more photons and
    // marks itself done (w of kSliceBase) for the later slices: in a pass of 90 slices most pixels
    // finish in the first, and the rest of the image need not reload its state 89 times. ----
    if (pc.sliceCount > 1u) {
        if (pc.slice > 0u) {
            kernelBase += block.v[bi + kSliceBase].xyz;
            kernelDifference += block.v[bi + kSliceDifference].xyz;
        }
        if (more) {
            block.v[bi + kSliceBase] = vec4(kernelBase, 0.0);
            block.v[bi + kSliceDifference] = vec4(kernelDifference, 0.0);
            return;
        }
        if (pc.slice + 1u < pc.sliceCount) block.v[bi + kSliceBase].w = 1.0;
    }

    // ---- The pass's sample (or its block's, when this pass completes it); accumulate ----
    vec3 base = gv.light + kernelBase, correction = vec3(0.0);
    if (unbiased && !completeBlock(block, bi, levels, level, done, base, correction, kernelDifference)) return;
    SampleSums sums = sampleSumsZero();
    sampleSumsAdd(sums, base, correction);
    sums.count = unbiased && kSchedule == kLevelSchedulePerPixel ? 1.0 : 0.0;  // film kChannelEstimateSq.w
    accumulateSums(AccumRef(uvec2(pc.accumLo, pc.accumHi)), pixelIndex, pc.width * pc.height, sums);
}

#include "loop_cap.glsl"

void main() {
    gatherPixel();
    // lanes whose loops lavapipe's cap may have ended: the host reports them (an error)
    if (loopCapReached(2u + (pc.width >> 31u)))
        atomicAdd(PhotonMapRef(uvec2(pc.headerLo, pc.headerHi)).h.loopCapHits, 1u);
}
