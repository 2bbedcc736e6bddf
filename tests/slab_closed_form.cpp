#include "slab_closed_form.h"

#include <cmath>

#include "render/film.h"

namespace telescope::test {

double slabTauFalloff() { return 3.0 * (1.0 - std::exp(-3.0)) / 3.0; }

std::vector<RegionMean> slabClosedForm(const Scene& scene, const shader::TrModel& model, uint32_t block,
                                       double constantScale, double falloffScale) {
    // The camera of absorbing-slab.json looks along +z; dirac filter: one direction per pixel.
    const Camera& cam = scene.camera;
    const double w = cam.width, h = cam.height;
    const double plane = 1.0 / std::tan(0.5 * cam.fovDegrees * 3.14159265358979323846 / 180.0);
    Film film(cam.width, cam.height);
    film.setSamplesPerPixel(1);
    for (uint32_t y = 0; y < cam.height; ++y)
        for (uint32_t x = 0; x < cam.width; ++x) {
            const double lx = -1.0 + 2.0 * (x + 0.5) / w, ly = h / w - 2.0 * (y + 0.5) / w;
            const double cosZ = plane / std::sqrt(lx * lx + ly * ly + plane * plane);
            const double tau = (ly > 0 ? kSlabTauConstant * constantScale : slabTauFalloff() * falloffScale) / cosZ;
            const double value = shader::trForm(model, shader::kFormSurfaceSurface, float(tau));
            film.sums(shader::kChannelEstimate)[size_t(y) * cam.width + x] = glm::dvec4(value, value, value, 0.0);
            film.sums(shader::kChannelEstimateSq)[size_t(y) * cam.width + x] = glm::dvec4(value * value);
        }
    return blockMeans(film, block);
}

std::vector<RegionMean> withOffsetAllowance(std::vector<RegionMean> exact) {
    for (RegionMean& r : exact) r.variance = glm::dvec3(2e-5 * r.mean) * glm::dvec3(2e-5 * r.mean);
    return exact;
}

}  // namespace telescope::test
