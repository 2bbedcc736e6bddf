// Scene helpers shared by the path tracer and the photon passes (GLSL only; included after the
// scene buffers and the specialisation constants kRayEpsilon and kLightCount).

// Offset along the geometric normal, to the side the next ray leaves from.
vec3 offsetRayOrigin(vec3 p, vec3 ng, vec3 dir) {
    float scale = max(max(abs(p.x), abs(p.y)), abs(p.z));
    float eps = max(kRayEpsilon, 4e-6 * scale);
    return p + (dot(dir, ng) >= 0.0 ? ng : -ng) * eps;
}

// Smallest light index whose inclusive cdf exceeds u (lights are picked by power).
uint pickLight(float u) {
    uint lo = 0u, hi = kLightCount - 1u;
    while (lo < hi) {
        uint mid = (lo + hi) >> 1u;
        if (u < lights[mid].cdf) hi = mid;
        else lo = mid + 1u;
    }
    return lo;
}

// Emitted radiance towards -dir at a point of prim with geometric normal ng (one-sided).
vec3 primEmission(Prim pr, vec3 dir, vec3 ng) {
    if (pr.light < 0 || dot(dir, ng) >= 0.0) return vec3(0.0);
    return lights[uint(pr.light)].radiance;
}
