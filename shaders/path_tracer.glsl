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
    if (bounce <= kMaxBounces) {
        r.base += c;
        return;
    }
    float w = depthWeight(kDebiasMode, pmf, kMaxBounces, level, bounce);
    if (w > 0.0) r.correction += c * w;
}

// Offset along the geometric normal, to the side the next ray leaves from.
vec3 offsetRayOrigin(vec3 p, vec3 ng, vec3 dir) {
    float scale = max(max(abs(p.x), abs(p.y)), abs(p.z));
    float eps = max(kRayEpsilon, 4e-6 * scale);
    return p + (dot(dir, ng) >= 0.0 ? ng : -ng) * eps;
}

// ---- Lights ----
uint pickLight(float u) {
    // Smallest index whose inclusive cdf exceeds u.
    uint lo = 0u, hi = kLightCount - 1u;
    while (lo < hi) {
        uint mid = (lo + hi) >> 1u;
        if (u < lights[mid].cdf) hi = mid;
        else lo = mid + 1u;
    }
    return lo;
}

// Solid-angle density with which next-event estimation picks a point on an emissive prim.
float areaLightPdf(uint lightIndex, float area, float dist, float cosLight) {
    return lights[lightIndex].pmf * dist * dist / max(cosLight * area, 1e-30);
}

// Emitted radiance towards -dir at a point of prim with geometric normal ng (one-sided).
vec3 primEmission(Prim pr, vec3 dir, vec3 ng) {
    if (pr.light < 0 || dot(dir, ng) >= 0.0) return vec3(0.0);
    return lights[uint(pr.light)].radiance;
}

// Next-event estimation from a Lambertian point p with normal n (facing the viewer):
// one light picked by power, one shadow ray, MIS against cosine sampling.
vec3 sampleDirectLambert(vec3 p, vec3 ng, vec3 n, vec3 albedo, inout Rng rng) {
    uint li = pickLight(rngNext(rng));
    LightGpu light = lights[li];
    float u1 = rngNext(rng), u2 = rngNext(rng);
    vec3 f = albedo * kInvPi;

    if (light.type == kLightPoint) {
        vec3 d = light.position - p;
        float dist2 = dot(d, d);
        float dist = sqrt(dist2);
        vec3 wi = d / dist;
        float cosS = dot(n, wi);
        if (cosS <= 0.0) return vec3(0.0);
        vec3 o = offsetRayOrigin(p, ng, wi);
        if (traceAny(o, wi, length(light.position - o) * (1.0 - 1e-5))) return vec3(0.0);
        return f * light.radiance * cosS / (dist2 * light.pmf);
    }
    if (light.type == kLightEnvironment) {
        vec3 wi = sampleUniformSphere(u1, u2);
        float cosS = dot(n, wi);
        if (cosS <= 0.0) return vec3(0.0);
        if (traceAny(offsetRayOrigin(p, ng, wi), wi, kInfinity)) return vec3(0.0);
        float pdfLight = light.pmf / (4.0 * kPi);
        float mis = powerHeuristic(pdfLight, cosS * kInvPi);
        return f * light.radiance * cosS * mis / pdfLight;
    }

    // Area light: a uniform point on the emissive prim.
    Prim pr = prims[light.prim];
    vec3 q, nq;
    if (kHasSpheres && pr.type == kPrimSphere) {
        nq = sampleUniformSphere(u1, u2);
        q = pr.p0 + nq * pr.p1.x;
    } else if (kHasDisks && pr.type == kPrimDisk) {
        q = sampleDisk(pr.p0, pr.n, pr.p1.x, u1, u2);
        nq = pr.n;
    } else {
        q = sampleTriangle(pr.p0, pr.p1, pr.p2, u1, u2);
        nq = pr.n;
    }
    vec3 d = q - p;
    float dist2 = dot(d, d);
    if (dist2 <= 0.0) return vec3(0.0);
    float dist = sqrt(dist2);
    vec3 wi = d / dist;
    float cosS = dot(n, wi);
    float cosL = -dot(wi, nq);
    if (cosS <= 0.0 || cosL <= 0.0) return vec3(0.0);
    vec3 o = offsetRayOrigin(p, ng, wi);
    float tMax = length(q - o);
    if (traceAny(o, wi, tMax * (1.0 - 1e-4))) return vec3(0.0);
    float pdfLight = areaLightPdf(li, pr.area, dist, cosL);
    float mis = powerHeuristic(pdfLight, cosS * kInvPi);
    return f * light.radiance * cosS * mis / pdfLight;
}

// ---- One camera path: all contributions up to the depth the level needs ----
PathResult tracePath(vec3 origin, vec3 dir, uint level, LevelPmf pmf, inout Rng rng) {
    PathResult r;
    r.base = vec3(0.0);
    r.correction = vec3(0.0);
    uint limit = min(depthLimit(kDebiasMode, kMaxBounces, level), kMaxTraceDepth);

    vec3 throughput = vec3(1.0);
    bool specularPrev = true;  // the camera "vertex" counts as specular for MIS
    float pdfPrev = 0.0;       // solid-angle pdf of the last BSDF sample

    for (uint v = 1u;; ++v) {
        Hit hit;
        if (!traceClosest(origin, dir, kInfinity, hit)) {
            if (kEnvironmentLight != 0xffffffffu) {
                LightGpu env = lights[kEnvironmentLight];
                float mis = (specularPrev || !kLightSampling) ? 1.0
                                                               : powerHeuristic(pdfPrev, env.pmf / (4.0 * kPi));
                addContribution(r, v - 1u, throughput * env.radiance * mis, pmf, level);
            }
            break;
        }
        Prim pr = prims[hit.prim];
        vec3 p = origin + dir * hit.t;
        vec3 ng = pr.n;
        if (kHasSpheres && pr.type == kPrimSphere) {
            ng = normalize(p - pr.p0);
            p = pr.p0 + ng * pr.p1.x;
        }

        // Emission reached by the last BSDF sample (or seen by the camera).
        vec3 le = primEmission(pr, dir, ng);
        if (any(greaterThan(le, vec3(0.0)))) {
            float mis = 1.0;
            if (!specularPrev && kLightSampling)
                mis = powerHeuristic(pdfPrev, areaLightPdf(uint(pr.light), pr.area, hit.t, -dot(dir, ng)));
            addContribution(r, v - 1u, throughput * le * mis, pmf, level);
        }
        if (v > limit) break;  // vertex v only adds light with v or more bounces

        MaterialGpu m = materials[pr.material];
        bool front = dot(dir, ng) < 0.0;
        vec3 n = front ? ng : -ng;  // faces the incoming ray

        if (m.type == kBsdfNull) break;
        if (m.type == kBsdfLambert) {
            if (!front && !kTwoSided) break;
            if (kLightSampling && kLightCount > 0u)
                addContribution(r, v, throughput * sampleDirectLambert(p, ng, n, m.albedo, rng), pmf, level);
            float u1 = rngNext(rng), u2 = rngNext(rng);
            dir = sampleCosineHemisphere(n, u1, u2);
            float cosO = dot(dir, n);
            if (cosO <= 0.0) break;
            pdfPrev = cosO * kInvPi;
            throughput *= m.albedo;
            specularPrev = false;
        } else if (kHasSpecular && m.type == kBsdfMirror) {
            dir = reflect(dir, n);
            throughput *= m.albedo;
            specularPrev = true;
        } else if (kHasSpecular && m.type == kBsdfDielectric) {
            // Smooth dielectric: reflect with probability F, else refract.
            float eta = front ? m.ior : 1.0 / m.ior;  // n_transmitted / n_incident
            float cosI = -dot(dir, n);
            float cosT;
            float F = fresnelDielectric(cosI, eta, cosT);
            bool refract = (m.flags & kMaterialRefraction) != 0u;
            if (!refract || rngNext(rng) < F) {
                dir = reflect(dir, n);
                if (!refract) throughput *= F;
            } else {
                dir = normalize(dir / eta + n * (cosI / eta - cosT));
            }
            throughput *= m.albedo;
            specularPrev = true;
        } else {
            break;
        }

        // Russian roulette as Tungsten does it: after bounce 2, once the throughput is small.
        if (v > 2u) {
            float q = maxComponent(throughput);
            if (q < 0.1) {
                if (rngNext(rng) >= q) break;
                throughput /= q;
            }
        }
        origin = offsetRayOrigin(p, ng, dir);
    }
    return r;
}
