// The path tracer with next-event estimation and MIS (GLSL only; included by
// path_trace.comp after the scene buffers, the specialisation constants and intersect.h).
//
// Bounces are counted as Tungsten counts them: light seen directly by the camera has 0
// bounces, light reaching the camera through b scattering vertices (specular ones included)
// has b. The contribution with b bounces goes to the base I(k) when b <= k, else it is a
// correction weighted by depthWeight() (shared/path_depth.h).

struct PathResult {
    vec3 base;
    vec3 correction;
};

// ---- Contribution bookkeeping ----
void addContribution(inout PathResult r, uint bounce, vec3 c, LevelPmf pmf, uint level) {
    if (bounce < kMinBounces) return;
    if (kPilot) {
        // pmf pilot: the base I(k) and the unweighted correction D_j = c_{j+1} of the fixed level.
        if (bounce <= kMaxBounces) r.base += c;
        else if (bounce == kMaxBounces + 1u + level) r.correction += c;
        return;
    }
    if (bounce <= kMaxBounces) {
        r.base += c;
        return;
    }
    float w = depthWeight(kDebiasMode, pmf, kMaxBounces, level, bounce);
    if (w > 0.0) r.correction += c * (w * kTestPmfWeight);
}

#include "scene_common.glsl"

// ---- Next-event estimation: one light sample and one shadow ray a step, whatever the vertex ----
// Lavapipe runs every branch of a SIMD group with masks, so a routine written at each kind of
// vertex's call site cost its whole work per site and step wherever the group's lanes held
// different kinds (media scenes: medium and surface vertices side by side). A Lambertian or medium
// vertex leaves a light query (the three random numbers of its light sample drawn where it
// scatters, as before); a glossy one samples its light itself and leaves a shadow query; pathStep
// samples the light of a light query and traces the shadow ray, once for every kind.
struct ShadowQuery {
    vec3 origin;
    vec3 dir;
    float tMax;
    vec3 value;           // the light's contribution at the vertex if the ray gets through
    vec3 throughput;      // the path's throughput at the vertex
    uint medium;          // the medium the ray starts in, index + 1 (0 = vacuum)
    uint bounce;          // the contribution's bounces before the forward surfaces the ray crosses
    bool startOnSurface;  // the transmittance's form at the ray's start
    bool pending;
};

ShadowQuery noShadowQuery() {
    ShadowQuery q;
    q.origin = vec3(0.0);
    q.dir = vec3(0.0, 0.0, 1.0);
    q.tMax = 0.0;
    q.value = vec3(0.0);
    q.throughput = vec3(0.0);
    q.medium = 0u;
    q.bounce = 0u;
    q.startOnSurface = true;
    q.pending = false;
    return q;
}

// A query for the shadow ray from surface point p (geometric normal ng) towards light sample ls.
ShadowQuery surfaceShadowQuery(vec3 p, vec3 ng, LightSample ls, vec3 value, vec3 throughput, uint medium, uint bounce) {
    ShadowQuery q;
    q.origin = offsetRayOrigin(p, ng, ls.wi);
    q.dir = ls.wi;
    q.tMax = ls.dist < kInfinity ? max(ls.dist - length(q.origin - p), 0.0) : kInfinity;
    q.value = value;
    q.throughput = throughput;
    q.medium = medium;
    q.bounce = bounce;
    q.startOnSurface = true;
    q.pending = any(greaterThan(value, vec3(0.0)));
    return q;
}

// Traces the query: the transmittance along its ray (media and pass-through surfaces) or its
// visibility, and `crossings`, the forward surfaces it passed (each a bounce, as in Tungsten).
vec3 traceShadowQuery(ShadowQuery q, inout Rng rng, out uint crossings) {
    crossings = 0u;
    if (kHasMedia || kHasPassThrough)
        return q.throughput * (q.value * shadowTransmittance(q.origin, q.dir, q.tMax, q.medium, q.startOnSurface, rng, crossings));
    if (traceAny(q.origin, q.dir, q.tMax)) return vec3(0.0);
    return q.throughput * q.value;
}

// The light sample a Lambertian or medium vertex asks for: one light picked by power, MIS against
// cosine or phase sampling.
struct LightQuery {
    vec3 p;           // the vertex
    vec3 ng;          // surface: the geometric normal (the shadow ray's offset)
    vec3 n;           // surface: the shading normal facing the viewer; medium: the path's direction
    vec3 albedo;      // surface: the Lambertian albedo
    vec3 throughput;  // the path's throughput at the vertex
    vec3 u;           // the light sample's random numbers (lightSampleNumbers)
    float g;          // medium: the phase function's g
    uint medium;      // the medium the shadow ray starts in, index + 1 (0 = vacuum)
    uint bounce;      // the vertex's bounce count
    bool inMedium;    // a medium vertex (phase function), else a Lambertian surface
    bool withMis;     // medium: false where the path ends here (no phase-sampled ray can find the light)
    bool pending;
};

LightQuery noLightQuery() {
    LightQuery q;
    q.p = vec3(0.0);
    q.ng = vec3(0.0, 0.0, 1.0);
    q.n = vec3(0.0, 0.0, 1.0);
    q.albedo = vec3(0.0);
    q.throughput = vec3(0.0);
    q.u = vec3(0.0);
    q.g = 0.0;
    q.medium = 0u;
    q.bounce = 0u;
    q.inMedium = false;
    q.withMis = false;
    q.pending = false;
    return q;
}

// A Lambertian point p with normal n (facing the viewer) reached with the given throughput as
// vertex `bounce`; with media the shadow ray starts in `medium` (index + 1).
LightQuery lambertLightQuery(vec3 p, vec3 ng, vec3 n, vec3 albedo, vec3 throughput, uint medium, uint bounce,
                             inout Rng rng) {
    LightQuery q = noLightQuery();
    q.p = p;
    q.ng = ng;
    q.n = n;
    q.albedo = albedo;
    q.throughput = throughput;
    q.u = lightSampleNumbers(rng);
    q.medium = medium;
    q.bounce = bounce;
    q.pending = true;
    return q;
}

// A scattering point p in medium mi (index), the path travelling along dir.
LightQuery mediumLightQuery(vec3 p, vec3 dir, uint mi, bool withMis, vec3 throughput, uint bounce, inout Rng rng) {
    LightQuery q = noLightQuery();
    q.p = p;
    q.n = dir;
    q.throughput = throughput;
    q.u = lightSampleNumbers(rng);
    q.g = mediumPhaseG(mi);
    q.medium = mi + 1u;
    q.bounce = bounce;
    q.inMedium = true;
    q.withMis = withMis;
    q.pending = true;
    return q;
}

// The light sample of a light query and its shadow ray.
ShadowQuery sampleDirect(LightQuery l) {
    LightSample ls;
    if (!sampleLightWith(l.p, l.u, ls)) return noShadowQuery();
    if (kHasMedia && l.inMedium) {
        float phase = phaseHG(dot(l.n, ls.wi), l.g);
        float mis = (l.withMis && ls.pdf > 0.0) ? powerHeuristic(ls.pdf, phase) : 1.0;
        ShadowQuery q;
        q.origin = l.p;
        q.dir = ls.wi;
        q.tMax = ls.dist;
        q.value = ls.weight * phase * mis;
        q.throughput = l.throughput;
        q.medium = l.medium;
        q.bounce = l.bounce;
        q.startOnSurface = false;
        q.pending = true;
        return q;
    }
    float cosS = dot(l.n, ls.wi);
    if (cosS <= 0.0) return noShadowQuery();
    float mis = ls.pdf > 0.0 ? powerHeuristic(ls.pdf, cosS * kInvPi) : 1.0;
    vec3 value = ls.weight * cosS * mis;
    if (!any(greaterThan(value, vec3(0.0)))) return noShadowQuery();
    return surfaceShadowQuery(l.p, l.ng, ls, l.albedo * kInvPi * value, l.throughput, l.medium, l.bounce);
}

#ifdef TELESCOPE_GLOSSY
// Next-event estimation from a glossy material (shared/bsdf.h glossy*): as sampleDirect's
// Lambertian case, with the BSDF evaluated in the local frame (t, b, n) for the viewer direction wi
// (local). The shadow ray starts in the medium on the light's side of the surface (prim, current
// medium).
ShadowQuery sampleDirectGlossy(vec3 p, vec3 ng, vec3 n, vec3 t, vec3 b, vec3 wi, MaterialGpu m, uint prim,
                               vec3 throughput, uint medium, uint bounce, inout Rng rng) {
    LightSample ls;
    if (!sampleLight(p, rng, ls)) return noShadowQuery();
    vec3 wo = vec3(dot(ls.wi, t), dot(ls.wi, b), dot(ls.wi, n));
    if (wo.z == 0.0) return noShadowQuery();
    vec3 f = glossyEval(m, wi, wo);
    if ((kBsdfFamilies & kFamilyRoughDielectric) != 0u && m.type == kBsdfRoughDielectric)
        f *= roughRefractionRadianceScale(m.ior, wi, wo);  // the BSDF-sampled paths' scaling, below
    if (!any(greaterThan(f, vec3(0.0)))) return noShadowQuery();
    float mis = ls.pdf > 0.0 ? powerHeuristic(ls.pdf, glossyPdf(m, wi, wo)) : 1.0;
    uint shadowMedium = kHasMedia ? mediumAcross(prim, ng, ls.wi, medium) : 0u;
    return surfaceShadowQuery(p, ng, ls, f * ls.weight * mis, throughput, shadowMedium, bounce);
}

#endif

// ---- One camera path as a state machine: pathStep() advances it by one vertex ----
// The compute pass interleaves samples: when a lane's path ends it starts its next sample at
// once, so lanes of a SIMD group do not wait for the longest path of the group.
struct PathState {
    vec3 origin;
    vec3 dir;
    vec3 throughput;
    float pdfPrev;      // solid-angle pdf of the last BSDF sample
    uint vertex;        // index of the vertex the next ray finds (1 = first hit)
    uint level;         // telescope level of this sample
    uint limit;         // deepest bounce with a non-zero weight
    bool specularPrev;  // the camera "vertex" counts as specular for MIS
    PathResult result;
    uint medium;        // participating medium the ray travels in, index + 1 (0 = vacuum)
    bool fromSurface;   // the last vertex is a surface (or the camera), not a medium point
    vec3 lastVertex;    // the last scattering vertex (for light pdfs across forward surfaces)
    uint mediumScatters;  // medium scattering events since the last surface (Tungsten's MediumState::bounce)
    float etaScale;     // product of the refractions' radiance scalings so far (Russian roulette divides it out)
};

PathState beginPath(vec3 origin, vec3 dir, uint level) {
    PathState s;
    s.origin = origin;
    s.dir = dir;
    s.throughput = vec3(1.0);
    s.pdfPrev = 0.0;
    s.vertex = 1u;
    s.level = level;
    s.limit = min(depthLimit(kDebiasMode, kMaxBounces, level), kMaxTraceDepth);
    s.specularPrev = true;
    s.result.base = vec3(0.0);
    s.result.correction = vec3(0.0);
    s.medium = kCameraMedium;
    s.fromSurface = true;
    s.lastVertex = origin;
    s.mediumScatters = 0u;
    s.etaScale = 1.0;
    return s;
}

// ---- A segment through a participating medium (medium.glsl): 0 reached the surface, 1 scattered
// in the medium (the state is advanced to the next vertex), 2 the path ends ----
uint mediumStep(inout PathState s, float tHit, LevelPmf pmf, inout Rng rng, inout LightQuery light) {
    uint mi = s.medium - 1u;
    // The medium's own limit (its max_bounces, Tungsten's sampleDistance): no free flight after
    // more than max_bounces scattering events in a row.
    if (s.mediumScatters > sceneMedium(mi).maxBounces) return 2u;
    vec3 p, emitted;
    bool scattered = sampleMediumSegment(mi, s.origin, s.dir, tHit, s.fromSurface, s.throughput, p, emitted, rng);
    uint v = s.vertex;
    // Medium emission at the collision that is vertex v counts v bounces (like light sampled from
    // there), so max_bounces k keeps it for v <= k, as Tungsten's loop does.
    if (kHasGrids && any(notEqual(emitted, vec3(0.0)))) addContribution(s.result, v, emitted, pmf, s.level);
    if (s.throughput == vec3(0.0)) return 2u;
    if (!scattered) return 0u;
    if (v > s.limit) return 2u;
    s.mediumScatters += 1u;
    // This vertex's phase-sampled ray will not be traced when the medium limit ends the path next.
    bool last = s.mediumScatters > sceneMedium(mi).maxBounces;
    if (kLightSampling && kLightCount > 0u) light = mediumLightQuery(p, s.dir, mi, !last, s.throughput, v, rng);
    if (last) return 2u;
    // Phase sampling: the phase function is sampled exactly, so the weight is 1.
    float g = mediumPhaseG(mi);
    float u1 = rngNext(rng), u2 = rngNext(rng);
    vec3 dir = samplePhaseHG(s.dir, g, u1, u2);
    s.pdfPrev = phaseHG(dot(s.dir, dir), g);
    s.dir = dir;
    s.specularPrev = false;
    s.fromSurface = false;
    s.origin = p;
    s.lastVertex = p;
    s.vertex = v + 1u;
    if (v > 1u) {
        float q = maxComponent(abs(s.throughput));
        if (q < 1.0) {
            if (rngNext(rng) >= q) return 2u;
            s.throughput /= q;
        }
    }
    return 1u;
}

// Traces the next ray of the path and scatters at the vertex it finds; false when the path ends.
// The vertex's next-event estimation is left in `light` or, from a glossy vertex, `shadow`.
bool pathScatter(inout PathState s, LevelPmf pmf, inout Rng rng, inout LightQuery light, inout ShadowQuery shadow) {
    uint v = s.vertex;
    Hit hit;
    bool found = traceClosest(s.origin, s.dir, kInfinity, hit);
    if (kHasMedia && s.medium != 0u) {
        // Media are enclosed by their boundaries, and an unbounded one absorbs all; a grid medium
        // is bounded by its box, so a ray may leave the scene through it (Tungsten's voxel medium).
        bool gridMedium = kHasGrids && sceneMedium(s.medium - 1u).type == kMediumGrid;
        if (!found && !gridMedium) return false;
        uint r = mediumStep(s, found ? hit.t : kInfinity, pmf, rng, light);
        if (r == 1u) return true;
        if (r == 2u) return false;
    }
    if (!found) {
        if (kEnvironmentLight != 0xffffffffu) {
            LightGpu env = sceneLight(kEnvironmentLight);
            float mis = (s.specularPrev || !kLightSampling) ? 1.0
                                                             : powerHeuristic(s.pdfPrev, environmentPdf(env, s.dir));
            addContribution(s.result, v - 1u, s.throughput * environmentRadiance(env, s.dir) * mis, pmf, s.level);
        }
        if (kCapLight != 0xffffffffu) {
            LightGpu cap = sceneLight(kCapLight);
            if (dot(s.dir, cap.position) >= cap.cosCap) {
                float pdf = cap.pmf / (2.0 * kPi * (1.0 - cap.cosCap));
                float mis = (s.specularPrev || !kLightSampling) ? 1.0 : powerHeuristic(s.pdfPrev, pdf);
                addContribution(s.result, v - 1u, s.throughput * cap.radiance * mis, pmf, s.level);
            }
        }
        return false;
    }
    Prim pr = BVH_PRIM(hit.prim);
    vec3 p, ng;
    hitPoint(pr, s.origin, s.dir, hit.t, p, ng);
    uint hitMedia = kHasMedia ? primMediaOf(hit.prim) : kPrimMediaNone;  // medium.glsl mediumAcross

    // Emission reached by the last BSDF sample (or seen by the camera).
    vec3 le = primEmission(pr, s.dir, ng);
    if (any(greaterThan(le, vec3(0.0)))) {
        float mis = 1.0;
        if (!s.specularPrev && kLightSampling) {
            float dist = (kHasMedia || kHasPassThrough) ? length(p - s.lastVertex) : hit.t;
            mis = powerHeuristic(s.pdfPrev, areaLightPdf(uint(pr.light), pr.area, dist, -dot(s.dir, ng)));
        }
        addContribution(s.result, v - 1u, s.throughput * le * mis, pmf, s.level);
    }
    if (v > s.limit) return false;  // vertex v only adds light with v or more bounces

    MaterialGpu m = sceneMaterial(pr.material);
    if (kHasTextures) applyTextures(m, pr, hit.prim, hit.bary, p);
    if (kHasMedia && m.type == kBsdfForward) {
        // Invisible medium boundary: the ray goes on; the crossing counts as a bounce (Tungsten).
        s.medium = mediumAcrossPacked(hitMedia, ng, s.dir, s.medium);
        s.origin = offsetRayOrigin(p, ng, s.dir);
        s.fromSurface = true;
        s.mediumScatters = 0u;
        s.vertex = v + 1u;
        return true;
    }
    vec3 ns = shadingNormal(hit.prim, hit.bary, ng);  // ng unless the triangle is smooth-shaded
    bool front = dot(s.dir, ns) < 0.0;
    vec3 n = front ? ns : -ns;  // faces the incoming ray
#ifdef TELESCOPE_GLOSSY
    // Mixed and transparency materials resolved to one material or a straight pass
    // (scene_common.glsl resolveComposite); thin sheets: straight on with probability mean(T)
    // (weight T / mean(T)), else the specular reflection (weight R / (1 - mean(T))):
    // shared/bsdf.h thinSheetScatter.
    // A straight pass is a bounce (Tungsten's loop counts every surface); it keeps the last
    // scattering vertex and its pdf for MIS, like a forward boundary.
    if ((kBsdfFamilies & (kFamilyMixed | kFamilyTransparency | kFamilyThinSheet)) != 0u) {
        uint index = pr.material;
        bool pass = resolveComposite(m, index, s.throughput, pr, hit.prim, hit.bary, p, rng);
        if (kHasMedia && m.type == kBsdfForward) pass = true;  // a forward boundary as a component
        bool reflected = false;
        if (!pass && (kBsdfFamilies & kFamilyThinSheet) != 0u && m.type == kBsdfThinSheet) {
            vec3 weight;
            reflected = thinSheetScatter(m, abs(dot(s.dir, ng)), rngNext(rng), weight);
            s.throughput *= weight;
            pass = !reflected;
        }
        if (pass) {
            if (kHasMedia) {
                s.medium = mediumAcrossPacked(hitMedia, ng, s.dir, s.medium);
                s.fromSurface = true;
                s.mediumScatters = 0u;
            }
            s.origin = offsetRayOrigin(p, ng, s.dir);
            s.vertex = v + 1u;
            return true;
        }
        if (reflected) {
            s.dir = reflect(s.dir, n);
            s.specularPrev = true;
        }
    }
#endif

    if (m.type == kBsdfLambert) {
        if (!front && !kTwoSided) return false;
        if (kLightSampling && kLightCount > 0u) {
            uint shadowMedium = kHasMedia ? mediumAcrossPacked(hitMedia, ng, -s.dir, s.medium) : 0u;
            light = lambertLightQuery(p, ng, n, m.albedo, s.throughput, shadowMedium, v, rng);
        }
        float u1 = rngNext(rng), u2 = rngNext(rng);
        s.dir = sampleCosineHemisphere(n, u1, u2);
        float cosO = dot(s.dir, n);
        if (cosO <= 0.0) return false;
        s.pdfPrev = cosO * kInvPi;
        s.throughput *= m.albedo;
        s.specularPrev = false;
    } else if (kHasSpecular && isSpecularBsdf(m.type)) {
        s.throughput *= scatterSpecular(m, front, n, s.dir, rng);
        // Radiance crossing a refraction scales by (n_camera side / n_light side)^2 (shared/bsdf.h):
        // it cancels on a path that leaves the dielectric again, and not where a light lies beyond an
        // open interface (Tungsten 0.2.2 renders the sky through a dielectric plate so).
        if (m.type == kBsdfDielectric && dot(s.dir, n) < 0.0) {
            float scale = refractionRadianceScale(m, front);
            s.throughput *= scale;
            s.etaScale *= scale;
        }
        s.specularPrev = true;
#ifdef TELESCOPE_GLOSSY
    } else if (kBsdfFamilies != 0u && isGlossyBsdf(m.type)) {
        // Local frame around the normal facing the viewer; a rough dielectric keeps the outward one.
        bool dielectric = (kBsdfFamilies & kFamilyRoughDielectric) != 0u && m.type == kBsdfRoughDielectric;
        if (!front && !kTwoSided && !dielectric) return false;
        vec3 nf = dielectric ? ns : n;
        vec3 t, b;
        buildFrame(nf, t, b);
        vec3 wi = vec3(dot(-s.dir, t), dot(-s.dir, b), dot(-s.dir, nf));
        if (kLightSampling && kLightCount > 0u)
            shadow = sampleDirectGlossy(p, ng, nf, t, b, wi, m, hit.prim, s.throughput, s.medium, v, rng);
        vec3 wo, weight;
        float pdf;
        bool specular;
        if (!glossySample(m, wi, rng, wo, weight, pdf, specular)) return false;
        s.dir = normalize(t * wo.x + b * wo.y + nf * wo.z);
        s.throughput *= weight;
        if (dielectric) {  // radiance scaling of a refraction, as at a smooth dielectric above
            float scale = roughRefractionRadianceScale(m.ior, wi, wo);
            s.throughput *= scale;
            s.etaScale *= scale;
        }
        s.pdfPrev = pdf;
        s.specularPrev = specular;
    } else if ((kBsdfFamilies & kFamilyThinSheet) != 0u && m.type == kBsdfThinSheet) {
        // reflected above (thinSheetScatter)
#endif
    } else {
        return false;  // null: black and opaque
    }

    // Russian roulette from the second bounce on: survive with probability max(throughput)
    // (pbrt's rule; Tungsten waits until the throughput is below 0.1). It changes the noise,
    // not the expectation, of every level. Derivative renders turn it off (kRoulette): its survival
    // decisions depend on the throughput, so they would differ between the parameter's values.
    if (kRoulette && v > 1u) {
        float q = maxComponent(abs(s.throughput)) / s.etaScale;
        if (q < 1.0) {
            if (rngNext(rng) >= q) return false;
            s.throughput /= q;
        }
    }
    s.origin = offsetRayOrigin(p, ng, s.dir);
    s.vertex = v + 1u;
    if (kHasMedia) {
        s.medium = mediumAcrossPacked(hitMedia, ng, s.dir, s.medium);
        s.fromSurface = true;
        s.mediumScatters = 0u;
    }
    if (kHasMedia || kHasPassThrough) s.lastVertex = p;
    return true;
}

// One step of the path: the vertex's scattering (pathScatter), then its light sample and shadow
// ray, if any; false when the path ends. The shadow ray's random numbers (stochastic transmittance
// estimators, thin sheets) are drawn after the vertex's own.
bool pathStep(inout PathState s, LevelPmf pmf, inout Rng rng) {
    LightQuery light = noLightQuery();
    ShadowQuery shadow = noShadowQuery();
    bool more = pathScatter(s, pmf, rng, light, shadow);
    if (light.pending) shadow = sampleDirect(light);
    if (shadow.pending) {
        uint crossings;
        vec3 direct = traceShadowQuery(shadow, rng, crossings);
        addContribution(s.result, shadow.bounce + crossings, direct, pmf, s.level);
    }
    return more;
}
