#include "render/gpu_scene.h"

#include "shared/bsdf.h"

#include <algorithm>
#include <cmath>
#include <functional>
#include <map>

#include <fmt/format.h>
#include <glm/gtc/constants.hpp>
#include <glm/gtc/matrix_access.hpp>

#include "core/error.h"
#include "render/environment_map.h"
#include "scene/density_grid.h"

namespace telescope {

namespace {

float luminanceOf(const glm::vec3& c) { return 0.2126f * c.x + 0.7152f * c.y + 0.0722f * c.z; }

Aabb boundsOf(const Geometry& g) {
    Aabb b;
    switch (g.type) {
        case GeometryType::Triangle:
            b.extend(g.p0);
            b.extend(g.p1);
            b.extend(g.p2);
            break;
        case GeometryType::Quad:
            b.extend(g.p0);
            b.extend(g.p1);
            b.extend(g.p2);
            b.extend(g.p1 + g.p2 - g.p0);
            break;
        case GeometryType::Sphere:
            b.extend(g.p0 - glm::vec3(g.radius));
            b.extend(g.p0 + glm::vec3(g.radius));
            break;
        case GeometryType::Disk: {
            // Extent of a disk along axis i: r * sqrt(1 - n_i^2).
            glm::vec3 e = g.radius * glm::sqrt(glm::max(glm::vec3(0.0f), 1.0f - g.normal * g.normal));
            b.extend(g.p0 - e);
            b.extend(g.p0 + e);
            break;
        }
    }
    return b;
}

float areaOf(const Geometry& g) {
    switch (g.type) {
        case GeometryType::Triangle: return 0.5f * glm::length(glm::cross(g.p1 - g.p0, g.p2 - g.p0));
        case GeometryType::Quad: return glm::length(glm::cross(g.p1 - g.p0, g.p2 - g.p0));
        case GeometryType::Sphere: return 4.0f * glm::pi<float>() * g.radius * g.radius;
        case GeometryType::Disk: return glm::pi<float>() * g.radius * g.radius;
    }
    return 0.0f;
}

}  // namespace

shader::MediumGpu mediumToGpu(const Medium& m, std::vector<float>& gridData) {
    shader::MediumGpu g{};
    g.sigmaT = m.sigmaA + m.sigmaS;
    g.sigmaS = m.sigmaS;
    g.type = uint32_t(m.type);
    g.density = m.density;
    g.falloffDir = m.falloffDirection;
    g.falloffScale = m.falloffScale;
    g.unitPoint = m.unitPoint;
    g.phase = uint32_t(m.phase);
    g.phaseG = m.phaseG;
    g.maxBounces = m.maxBounces;
    g.model.type = m.transmittance.type;
    g.model.typeA = m.transmittance.typeA;
    g.model.typeB = m.transmittance.typeB;
    g.model.ratio = m.transmittance.ratio;
    g.model.a = m.transmittance.params;
    g.model.b = m.transmittance.paramsB;
    if (m.type == MediumType::Grid) {
        // Voxels scaled by the medium density; the majorant grid and the bounds of the whole grid
        // for the trackers; then the emission.
        const DensityGrid& grid = m.grid;
        const glm::mat4 worldToUnit = glm::inverse(grid.unitToWorld);
        g.gridRow0 = glm::row(worldToUnit, 0);
        g.gridRow1 = glm::row(worldToUnit, 1);
        g.gridRow2 = glm::row(worldToUnit, 2);
        g.gridRes = grid.resolution;
        g.gridOffset = uint32_t(gridData.size());
        DensityGrid scaled;
        scaled.resolution = grid.resolution;
        scaled.majorantCell = grid.majorantCell;
        scaled.majorantCoversStencil = grid.majorantCoversStencil;
        scaled.density.reserve(grid.density.size());
        float lo = INFINITY, hi = 0.0f;
        for (float d : grid.density) {
            scaled.density.push_back(d * m.density);
            lo = std::min(lo, d * m.density);
            hi = std::max(hi, d * m.density);
        }
        gridData.insert(gridData.end(), scaled.density.begin(), scaled.density.end());
        g.gridMinDensity = std::isfinite(lo) ? lo : 0.0f;
        g.gridMaxDensity = hi;
        g.majorantRes = majorantResolution(grid);
        g.majorantScale = grid.majorantCell == 0 ? glm::vec3(1.0f) : glm::vec3(grid.resolution) / float(grid.majorantCell);
        g.majorantOffset = uint32_t(gridData.size());
        for (glm::vec2 mm : majorantGrid(scaled)) {
            gridData.push_back(mm.x);
            gridData.push_back(mm.y);
        }
        g.gridFlags = grid.nearest ? shader::kGridNearest : 0u;
        if (!grid.emission.empty()) {
            g.gridFlags |= shader::kGridEmission | (grid.emissionByDensity ? shader::kGridEmissionByDensity : 0u);
            g.emissionOffset = uint32_t(gridData.size());
            gridData.insert(gridData.end(), grid.emission.begin(), grid.emission.end());
        }
    }
    return g;
}

shader::MaterialGpu gpuMaterial(const Material& m, double diffuseFresnel) {
    shader::MaterialGpu g{};
    g.albedo = m.albedo;
    g.type = uint32_t(m.type);
    g.ior = m.ior;
    g.flags = m.enableRefraction ? shader::kMaterialRefraction : 0u;
    g.roughness = m.roughness;
    g.distribution = m.distribution;
    g.eta = m.eta;
    g.k = m.k;
    g.albedoTexture = m.albedoTexture >= 0 ? uint32_t(m.albedoTexture) : shader::kNoTexture;
    g.roughnessTexture = m.roughnessTexture >= 0 ? uint32_t(m.roughnessTexture) : shader::kNoTexture;
    g.component0 = m.component[0];
    g.component1 = m.component[1];
    g.ratio = m.ratio;
    g.alpha = m.alpha;
    if (m.type == BsdfType::ThinSheet) {
        g.roughness = m.thickness;
        g.k = m.thickness * m.sigmaA;  // tau
        if (m.enableInterference) g.flags |= shader::kMaterialInterference;
    }
    if (m.type == BsdfType::Plastic || m.type == BsdfType::RoughPlastic) {
        g.diffuseFresnel = float(diffuseFresnel < 0.0 ? plasticDiffuseFresnel(m.ior) : diffuseFresnel);
        g.k = m.thickness * m.sigmaA;  // tau
        g.substrateWeight = (m.albedo.x + m.albedo.y + m.albedo.z) / 3.0f * std::exp(-2.0f * (g.k.x + g.k.y + g.k.z) / 3.0f);
    }
    return g;
}

double plasticDiffuseFresnel(float ior) {
    // Trapezoid rule in mu^2 with a million steps, as Tungsten computes it, in double precision.
    const int n = 1000000;
    float cosT;
    double sum = 0.0, fb = shader::fresnelDielectric(0.0f, 1.0f / ior, cosT);
    for (int i = 1; i <= n; ++i) {
        const double fa = shader::fresnelDielectric(std::min(float(std::sqrt(double(i) / n)), 1.0f), 1.0f / ior, cosT);
        sum += (fa + fb) * (0.5 / n);
        fb = fa;
    }
    return sum;
}

// A surface that only separates two media: a dielectric that refracts, a rough dielectric, a
// forward (index-matched) medium boundary. Where one coincides with another surface the ray hits
// the other (kPrimInterface; shared/intersect.h "Coincident surfaces"). Composites are not.
static bool isInterface(const shader::MaterialGpu& m) {
    return (m.type == shader::kBsdfDielectric && (m.flags & shader::kMaterialRefraction) != 0u) ||
           m.type == shader::kBsdfRoughDielectric || m.type == shader::kBsdfForward;
}

GpuScene buildGpuScene(const Scene& scene) {
    GpuScene out;
    SceneFeatures& f = out.features;

    // ---- Materials ----
    std::map<float, double> diffuseFresnelByIor;
    for (const Material& m : scene.materials) {
        double diffuseFresnel = 0.0;  // plastics only; one computation per index of refraction
        if (m.type == BsdfType::Plastic || m.type == BsdfType::RoughPlastic) {
            auto [it, added] = diffuseFresnelByIor.try_emplace(m.ior, 0.0);
            if (added) it->second = plasticDiffuseFresnel(m.ior);
            diffuseFresnel = it->second;
        }
        const shader::MaterialGpu g = gpuMaterial(m, diffuseFresnel);
        out.materials.push_back(g);
        if (shader::isSpecularBsdf(uint32_t(m.type))) f.specular = true;
        f.bsdfFamilies |= shader::bsdfFamily(uint32_t(m.type));
        f.textures = f.textures || m.albedoTexture >= 0 || m.roughnessTexture >= 0;
        if (m.type == BsdfType::Forward) f.media = true;
    }
    // Photon mapping stores photons on both sides of a rough dielectric and of a composite that may
    // resolve to one (the store comes before the composite's draw: photon_trace.comp). Composites
    // nest at most kMaxMaterialNesting deep and never contain themselves (the reader's rules).
    const std::function<bool(uint32_t)> mayTransmit = [&](uint32_t i) {
        const Material& m = scene.materials[i];
        if (m.type == BsdfType::Mixed) return mayTransmit(m.component[0]) || mayTransmit(m.component[1]);
        if (m.type == BsdfType::Transparency) return mayTransmit(m.component[0]);
        return m.type == BsdfType::RoughDielectric;
    };
    for (uint32_t i = 0; i < scene.materials.size(); ++i)
        if (mayTransmit(i)) out.materials[i].flags |= shader::kMaterialBothSides;
    if (out.materials.empty()) out.materials.push_back({});  // keep the buffer non-empty

    // ---- BVH over the geometry; prims are stored in leaf order ----
    std::vector<Aabb> boxes;
    boxes.reserve(scene.geometry.size());
    Aabb all;
    for (const Geometry& g : scene.geometry) {
        boxes.push_back(boundsOf(g));
        all.extend(boxes.back());
    }
    f.sceneExtent = scene.geometry.empty() ? 1.0f : glm::length(all.hi - all.lo);
    if (!(f.sceneExtent > 0.0f) || !std::isfinite(f.sceneExtent)) f.sceneExtent = 1.0f;
    f.sceneCentre = scene.geometry.empty() ? glm::vec3(0.0f) : 0.5f * (all.lo + all.hi);
    Bvh bvh = buildBvh(boxes);
    out.nodes = collapseBvh(bvh);
    f.bvhStackNeed = bvhStackNeed(out.nodes);

    // ---- Prims and area lights ----
    std::vector<float> power;
    std::vector<glm::vec4> uvRecords;  // two per prim slot (shared/texture.h primUv), textured scenes only
    // Three vec4 per prim slot (kBindingShadingNormals), only in scenes with smooth triangles.
    f.smoothNormals = std::any_of(scene.geometry.begin(), scene.geometry.end(), [](const Geometry& g) { return g.smooth; });
    if (f.smoothNormals) out.shadingNormals.reserve(3 * bvh.order.size());
    else out.shadingNormals.assign(1, glm::vec4(0.0f));
    out.prims.reserve(bvh.order.size());
    for (uint32_t slot = 0; slot < bvh.order.size(); ++slot) {
        const Geometry& g = scene.geometry[bvh.order[slot]];
        shader::Prim p{};
        p.type = uint32_t(g.type);
        if (isInterface(out.materials.at(g.material))) {
            p.type |= shader::kPrimInterface;
            f.interfaces = true;
        }
        p.material = g.material;
        p.p0 = g.p0;
        const bool planar = g.type == GeometryType::Triangle || g.type == GeometryType::Quad;
        p.p1 = planar ? g.p1 : glm::vec3(g.radius, 0.0f, 0.0f);
        p.p2 = planar ? g.p2 : glm::vec3(0.0f);
        p.n = g.normal;
        p.area = areaOf(g);
        p.light = -1;
        if (g.type == GeometryType::Sphere) f.spheres = true;
        if (g.type == GeometryType::Disk) f.disks = true;
        float lum = luminanceOf(g.emission);
        if (lum > 0.0f && p.area > 0.0f) {
            p.light = int32_t(out.lights.size());
            shader::LightGpu l{};
            l.type = shader::kLightArea;
            l.radiance = g.emission;
            l.prim = slot;
            out.lights.push_back(l);
            power.push_back(lum * glm::pi<float>() * p.area);
            f.areaLights = true;
        }
        if (f.textures) {
            if (planar) {
                uvRecords.push_back({g.uv[0], g.uv[1]});
                uvRecords.push_back({g.uv[2], 0.0f, 0.0f});
            } else {
                const float invRadius = g.type == GeometryType::Disk && g.radius > 0.0f ? 1.0f / g.radius : 0.0f;
                uvRecords.push_back({g.uvFrame[0], invRadius});
                uvRecords.push_back({g.uvFrame[1], 0.0f});
            }
        }
        if (f.smoothNormals)  // (n0, 1) (n1, 0) (n2, 0) for a smooth triangle; w = 0 reads the geometric normal
            for (int k = 0; k < 3; ++k)
                out.shadingNormals.push_back(g.smooth ? glm::vec4(g.vertexNormal[k], k == 0 ? 1.0f : 0.0f) : glm::vec4(0.0f));
        out.prims.push_back(p);
        out.primMedia.push_back(g.hasMedia ? uint32_t(g.intMedium + 1) | (uint32_t(g.extMedium + 1) << 16)
                                           : shader::kPrimMediaNone);
    }

    // ---- Point lights and the environment ----
    for (const PointLikeLight& pl : scene.lights) {
        const glm::vec3 intensity = pl.image ? environmentMeanRadiance(*pl.image) : pl.intensity;
        float lum = luminanceOf(intensity);
        if (!(lum > 0.0f)) continue;
        shader::LightGpu l{};
        l.radiance = intensity;
        if (pl.type == LightType::Point) {
            l.type = uint32_t(pl.type);  // LightType takes its values from kLight*
            l.position = pl.position;
            power.push_back(4.0f * glm::pi<float>() * lum);
            f.pointLights = true;
        } else if (pl.type == LightType::Cap) {
            // Power for light selection: the flux through the scene's disk, as for the environment.
            l.type = uint32_t(pl.type);
            l.position = pl.direction;
            l.cosCap = pl.cosCap;
            float r = 0.5f * f.sceneExtent;
            power.push_back(lum * 2.0f * glm::pi<float>() * (1.0f - pl.cosCap) * glm::pi<float>() * r * r);
            f.capLight = uint32_t(out.lights.size());
        } else {
            if (f.environment) continue;  // one environment; the loader rejects more
            l.type = uint32_t(pl.type);
            float r = 0.5f * f.sceneExtent;
            power.push_back(lum * glm::pi<float>() * 4.0f * glm::pi<float>() * r * r);
            f.environment = true;
            f.environmentLight = uint32_t(out.lights.size());
            if (pl.image) {
                // The image, its rotation and sampling tables (shaders/shared/environment_map.h); the
                // light's radiance is the mean, for light selection by power.
                out.environment = buildEnvironmentBuffer(*pl.image, pl.rotation);
                f.environmentMap = true;
            }
        }
        out.lights.push_back(l);
    }

    // ---- Light selection pmf and inclusive cdf ----
    double total = 0.0;
    for (float p : power) total += p;
    double running = 0.0;
    for (size_t i = 0; i < out.lights.size(); ++i) {
        out.lights[i].pmf = float(power[i] / total);
        running += power[i];
        out.lights[i].cdf = i + 1 == out.lights.size() ? 1.0f : float(running / total);
    }
    f.lightCount = uint32_t(out.lights.size());
    if (out.lights.empty()) out.lights.push_back({});
    if (out.prims.empty()) out.prims.push_back({});

    // ---- Participating media ----
    for (const Medium& m : scene.media) out.media.push_back(mediumToGpu(m, out.gridData));
    f.mediumCount = uint32_t(scene.media.size());
    f.media = f.media || !scene.media.empty();
    for (const Medium& m : scene.media) {
        f.grids = f.grids || m.type == MediumType::Grid;
        f.inhomogeneous = f.inhomogeneous || m.type != MediumType::Homogeneous;
    }
    if (out.media.empty()) out.media.push_back({});
    if (out.gridData.empty()) out.gridData.push_back(0.0f);
    if (out.environment.empty()) out.environment.push_back(0.0f);
    while (out.primMedia.size() < out.prims.size()) out.primMedia.push_back(shader::kPrimMediaNone);
    // ---- Textures: header, table, uv records, texels (shared/texture.h) ----
    if (f.textures) {
        f.textureCount = uint32_t(scene.textures.size());
        const uint64_t uvBase = 1 + 3 * uint64_t(scene.textures.size());
        uint64_t texels = 0;
        for (const Texture& t : scene.textures) texels += t.texels.size();
        const uint64_t total = uvBase + uvRecords.size() + texels;
        if (total * sizeof(glm::vec4) > kMaxTextureBytes)
            throw InputError(scene.path, "bsdfs",
                             fmt::format("the textures ({} texels) and the uv records of {} primitives need {} MiB, more "
                                         "than the {} MiB of one texture binding",
                                         texels, uvRecords.size() / 2, (total * sizeof(glm::vec4)) >> 20,
                                         kMaxTextureBytes >> 20));
        out.textureData.reserve(total);
        out.textureData.push_back({glm::uintBitsToFloat(uint32_t(uvBase)), glm::uintBitsToFloat(f.textureCount), 0.0f, 0.0f});
        uint64_t texelOffset = uvBase + uvRecords.size();
        for (const Texture& t : scene.textures) {
            const uint32_t flags = (t.interpolate ? shader::kTextureInterpolate : 0u) | (t.clamp ? shader::kTextureClamp : 0u);
            const bool bitmap = t.type == TextureType::Bitmap;
            out.textureData.push_back({t.on, glm::uintBitsToFloat(uint32_t(t.type))});
            out.textureData.push_back({t.off, glm::uintBitsToFloat(flags)});
            out.textureData.push_back({glm::uintBitsToFloat(t.resU), glm::uintBitsToFloat(t.resV),
                                       glm::uintBitsToFloat(bitmap ? uint32_t(texelOffset) : 0u), 0.0f});
            if (bitmap) texelOffset += t.texels.size();
        }
        out.textureData.insert(out.textureData.end(), uvRecords.begin(), uvRecords.end());
        for (const Texture& t : scene.textures) out.textureData.insert(out.textureData.end(), t.texels.begin(), t.texels.end());
    }
    if (out.textureData.empty()) out.textureData.push_back(glm::vec4(0.0f));
    f.fitsUniforms = out.nodes.size() <= shader::kMaxUniformNodes && out.prims.size() <= shader::kMaxUniformPrims;
    f.tablesFitUniforms = out.materials.size() <= shader::kMaxUniformMaterials &&
                          out.lights.size() <= shader::kMaxUniformLights && out.media.size() <= shader::kMaxUniformMedia;
    f.primCount = uint32_t(out.prims.size());
    f.bruteForcePrims = f.fitsUniforms && out.prims.size() <= shader::kMaxBruteForcePrims ? uint32_t(out.prims.size()) : 0u;
    static_assert(shader::kMaxBruteForcePrims <= 32u, "kSpecBruteForceCurved holds a bit per brute-force slot");
    for (uint32_t i = 0; i < f.bruteForcePrims; ++i)
        if (shader::primShape(out.prims[i]) == shader::kPrimSphere || shader::primShape(out.prims[i]) == shader::kPrimDisk)
            f.bruteForceCurved |= 1u << i;
    return out;
}

}  // namespace telescope
