#include "study/methods.h"

#include <charconv>

#include <fmt/format.h>

#include "core/error.h"

namespace telescope {

namespace {

struct Preset {
    const char* name;
    const char* description;
    // Overrides for level k.
    std::vector<SceneOverride> (*make)(uint32_t k);
};

std::vector<SceneOverride> pathDepth(uint32_t k, const char* estimator, const char* pmf = R"({"type":"geometric","r":0.65})") {
    // k bounces: max_bounces counts the light connection (pathDepthK, src/scene/scene.h).
    std::vector<SceneOverride> o = {{"integrator.max_bounces", std::to_string(k + 1)}};
    if (estimator)
        o.push_back({"integrator.debias", fmt::format(R"({{"estimator":"{}","pmf":{}}})", estimator, pmf)});
    else
        o.push_back({"integrator.debias", "null"});
    return o;
}

const Preset kPresets[] = {
    {"biased", "path tracing truncated at k bounces, I(k)", [](uint32_t k) { return pathDepth(k, nullptr); }},
    {"single_term", "debiased path depth, single-term estimator at base k, geometric pmf r = 0.65",
     [](uint32_t k) { return pathDepth(k, "single_term"); }},
    {"sum", "debiased path depth, Russian-roulette sum estimator at base k, geometric pmf r = 0.65",
     [](uint32_t k) { return pathDepth(k, "sum"); }},
    {"single_term_power", "debiased path depth, single-term estimator at base k, power-law pmf alpha = 2/3",
     [](uint32_t k) { return pathDepth(k, "single_term", R"({"type":"power_law"})"); }},
    {"single_term_auto", "debiased path depth, single-term estimator at base k, pmf chosen by a pilot (pilot time counted)",
     [](uint32_t k) { return pathDepth(k, "single_term", R"({"type":"auto"})"); }},
};

std::string trim(const std::string& s) {
    size_t a = s.find_first_not_of(" \t"), b = s.find_last_not_of(" \t");
    return a == std::string::npos ? std::string() : s.substr(a, b - a + 1);
}

}  // namespace

std::string describePresets() {
    std::string s;
    for (const auto& p : kPresets) s += fmt::format("  {}:K  {}\n", p.name, p.description);
    return s;
}

Method parseMethod(const std::string& specIn, const std::string& option) {
    const std::string spec = trim(specIn);
    size_t colon = spec.find(':');
    if (colon == std::string::npos || colon == 0)
        throw InputError("", option, fmt::format("'{}' is not PRESET:K or LABEL: key=value; ...", spec));
    const std::string head = spec.substr(0, colon), rest = trim(spec.substr(colon + 1));

    // A preset: NAME:K with K a non-negative integer.
    for (const auto& p : kPresets) {
        if (head != p.name) continue;
        uint32_t k = 0;
        auto [end, ec] = std::from_chars(rest.data(), rest.data() + rest.size(), k);
        if (ec != std::errc() || end != rest.data() + rest.size())
            throw InputError("", option, fmt::format("'{}': the level after '{}:' must be an integer", spec, head));
        return Method{spec, p.make(k), fmt::format("{} (k = {})", p.description, k)};
    }
    // A custom method: LABEL: key=value; key=value.
    if (rest.find('=') == std::string::npos)
    {
        std::string known;
        for (const auto& p : kPresets) known += (known.empty() ? "" : ", ") + std::string(p.name) + ":K";
        throw InputError("", option,
                         fmt::format("unknown preset '{}' (known: {}) and no key=value overrides given", head, known));
    }
    Method m{head, {}, ""};
    size_t start = 0;
    while (start <= rest.size()) {
        size_t semi = rest.find(';', start);
        std::string item = trim(rest.substr(start, semi == std::string::npos ? std::string::npos : semi - start));
        if (!item.empty()) {
            m.overrides.push_back(parseOverride(item));
            m.description += (m.description.empty() ? "" : "; ") + item;
        }
        if (semi == std::string::npos) break;
        start = semi + 1;
    }
    return m;
}

}  // namespace telescope
