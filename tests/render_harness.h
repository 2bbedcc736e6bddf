// Helpers for tests that render on the Vulkan device: one shared Context (validation on when
// TELESCOPE_VALIDATION=1, as CTest sets it), scene loading from the source tree, and renders to a
// Film with a given seed.
#pragma once

#include <memory>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "gpu/context.h"
#include "render/film.h"
#include "render/pmf_pilot.h"
#include "render/renderer.h"
#include "scene/scene_loader.h"

namespace telescope::test {

gpu::Context& sharedContext();
std::string sourcePath(const std::string& relative);
Scene loadTestScene(const std::string& relative, const std::vector<SceneOverride>& overrides = {});
// The scene as a Renderer takes it (render/resolved_scene.h), on the shared context: a pilot
// runs only for a pmf "auto" (seeded from `seed`).
ResolvedScene resolved(const Scene& scene, uint32_t seed = 1);
Film renderFilm(const Scene& scene, uint64_t spp, uint32_t seed);

// Batch means of one render, [region][batch], per colour channel: `batches` renders of
// `samplesPerBatch` samples each, continuing one Renderer (regions: blocks of `block` x `block`
// pixels, row-major). For estimators whose variance may be infinite (unbiased photon mapping): the
// batches' own spread stands in for a variance that may not exist (region_stats.h compareBatchMeans).
std::vector<std::vector<glm::dvec3>> regionBatchMeans(const Scene& scene, uint32_t block, uint32_t batches,
                                                      uint32_t samplesPerBatch, uint32_t seed);

// Fails the current test if lavapipe's loop cap ended loops or the loop budget dropped samples.
void expectLoopsComplete(const RenderStats& stats);

// Fails the current test if the validation layer reported anything.
void expectNoValidationMessages();

// The largest |a - b| / (|b| + floor) over every component of every channel sum.
double largestRelativeDifference(const Film& a, const Film& b, double floor);

}  // namespace telescope::test
