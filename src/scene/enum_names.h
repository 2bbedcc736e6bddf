// The names of the settings' enums as the scene file spells them: one table per enum, used by the
// validating reader (settings_reader.cpp), by the settings' JSON in both directions
// (settings_json.cpp) and by every text that names a value (plan, metadata).
#pragma once

#include <algorithm>
#include <cstddef>
#include <optional>
#include <stdexcept>
#include <string>
#include <string_view>

#include "scene/scene.h"

namespace telescope {

template <class E>
struct Named {
    E value;
    const char* name;
};

inline constexpr Named<PmfType> kPmfTypeNames[] = {
    {PmfType::Geometric, "geometric"}, {PmfType::PowerLaw, "power_law"}, {PmfType::Auto, "auto"}};
inline constexpr Named<DebiasEstimator> kDebiasEstimatorNames[] = {
    {DebiasEstimator::SingleTerm, "single_term"}, {DebiasEstimator::Sum, "sum"}};
inline constexpr Named<LevelSchedule> kLevelScheduleNames[] = {
    {LevelSchedule::PerPixel, "per_pixel"}, {LevelSchedule::Uniform, "uniform"}, {LevelSchedule::Queued, "queued"}};
inline constexpr Named<IntegratorType> kIntegratorTypeNames[] = {
    {IntegratorType::PathTracer, "path_tracer"},
    {IntegratorType::PhotonMap, "photon_map"},
    {IntegratorType::ProgressivePhotonMap, "progressive_photon_map"}};
inline constexpr Named<PhotonKernel> kPhotonKernelNames[] = {
    {PhotonKernel::Cone, "cone"}, {PhotonKernel::Uniform, "uniform"}, {PhotonKernel::Epanechnikov, "epanechnikov"}};
inline constexpr Named<DirectLighting> kDirectLightingNames[] = {
    {DirectLighting::Photons, "photons"}, {DirectLighting::NextEvent, "next_event"}};
inline constexpr Named<TransmittanceEstimatorType> kTransmittanceEstimatorNames[] = {
    {TransmittanceEstimatorType::RayMarch, "ray_march"},
    {TransmittanceEstimatorType::DebiasedRayMarch, "debiased_ray_march"},
    {TransmittanceEstimatorType::DeltaTracking, "delta_tracking"},
    {TransmittanceEstimatorType::RatioTracking, "ratio_tracking"},
    {TransmittanceEstimatorType::ResidualRatioTracking, "residual_ratio_tracking"},
    {TransmittanceEstimatorType::UnbiasedRayMarch, "unbiased_ray_march"},
    {TransmittanceEstimatorType::Taylor, "taylor"}};

inline constexpr Named<PixelFilter> kPixelFilterNames[] = {
    {PixelFilter::Dirac, "dirac"},
    {PixelFilter::Box, "box"},
    {PixelFilter::Tent, "tent"},
    {PixelFilter::Gaussian, "gaussian"},
    {PixelFilter::MitchellNetravali, "mitchell_netravali"},
    {PixelFilter::CatmullRom, "catmull_rom"},
    {PixelFilter::Lanczos, "lanczos"}};

template <class E, size_t N>
const char* nameOf(const Named<E> (&table)[N], E value) {
    for (const Named<E>& n : table)
        if (n.value == value) return n.name;
    throw std::logic_error("a settings value without a name");
}

template <class E, size_t N>
std::optional<E> valueOf(const Named<E> (&table)[N], std::string_view name) {
    for (const Named<E>& n : table)
        if (name == n.name) return n.value;
    return std::nullopt;
}

// "\"a\", \"b\" or \"c\"": the names for an error message, the first `count` of the table (all
// by default).
template <class E, size_t N>
std::string expectedNames(const Named<E> (&table)[N], size_t count = N) {
    std::string s;
    for (size_t i = 0; i < count && i < N; ++i) {
        if (i > 0) s += i + 1 == std::min(count, N) ? " or " : ", ";
        s += std::string("\"") + table[i].name + "\"";
    }
    return s;
}

}  // namespace telescope
