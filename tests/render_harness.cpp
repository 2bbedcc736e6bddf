#include "render_harness.h"

#include "region_stats.h"

#include <algorithm>
#include <cmath>

namespace telescope::test {

gpu::Context& sharedContext() {
    static gpu::Context context{gpu::ContextOptions{}};
    return context;
}

std::string sourcePath(const std::string& relative) { return std::string(TELESCOPE_SOURCE_DIR) + "/" + relative; }

Scene loadTestScene(const std::string& relative, const std::vector<SceneOverride>& overrides) {
    return loadScene(sourcePath(relative), overrides);
}

ResolvedScene resolved(const Scene& scene, uint32_t seed) { return resolveScene(sharedContext(), scene, seed).scene; }

Film renderFilm(const Scene& scene, uint64_t spp, uint32_t seed) {
    Renderer renderer(sharedContext(), resolved(scene), seed);
    RenderRequest request;
    request.spp = spp;
    renderer.render(request);
    expectLoopsComplete(renderer.stats());
    return renderer.film();
}

std::vector<std::vector<glm::dvec3>> regionBatchMeans(const Scene& scene, uint32_t block, uint32_t batches,
                                                      uint32_t samplesPerBatch, uint32_t seed) {
    std::vector<std::vector<glm::dvec3>> out;
    std::vector<glm::dvec3> before;
    Renderer renderer(sharedContext(), resolved(scene), seed);
    for (uint32_t b = 0; b < batches; ++b) {
        RenderRequest request;
        request.spp = samplesPerBatch;
        renderer.render(request);
        expectLoopsComplete(renderer.stats());
        const Film film = renderer.film();
        const double n = double(film.samplesPerPixel());
        const std::vector<RegionMean> means = blockMeans(film, block);
        out.resize(means.size());
        before.resize(means.size(), glm::dvec3(0.0));
        for (size_t r = 0; r < means.size(); ++r) {
            const glm::dvec3 sum = means[r].mean * n;
            out[r].push_back((sum - before[r]) / double(samplesPerBatch));
            before[r] = sum;
        }
    }
    return out;
}

void expectLoopsComplete(const RenderStats& stats) {
    EXPECT_EQ(stats.loops.capHits, 0u) << "lavapipe's loop cap was reached: loops ended early";
    EXPECT_EQ(stats.loops.overlong, 0u) << "samples dropped by the loop budget";
}

void expectNoValidationMessages() {
    EXPECT_EQ(sharedContext().validationMessageCount(), 0u) << "Vulkan validation reported problems";
}

double largestRelativeDifference(const Film& a, const Film& b, double floor) {
    double worst = 0.0;
    for (uint32_t c = 0; c < shader::kChannelCount; ++c)
        for (size_t i = 0; i < a.pixelCount(); ++i)
            for (int k = 0; k < 4; ++k) {
                const double x = a.sums(c)[i][k], y = b.sums(c)[i][k];
                worst = std::max(worst, std::abs(x - y) / (std::abs(y) + floor));
            }
    return worst;
}

}  // namespace telescope::test
