#include "cli/shard.h"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <numeric>
#include <sstream>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "session/outputs.h"
#include "core/atomic_file.h"
#include "core/error.h"
#include "render/film_io.h"
#include "scene/scene_loader.h"
#include "scene/settings_json.h"

namespace fs = std::filesystem;

namespace telescope::cli {

using namespace session;  // the session layer: loading, outputs, checks

namespace {

// The merge's note on a checkpoint whose block in progress it leaves out.
std::string blockLeftOut(const std::string& path, const std::string& block) {
    return path + ": " + block + " is not in the merge; resume that render to finish it, then merge again";
}

std::string seedList(const std::vector<uint32_t>& seeds) {
    std::string s;
    for (size_t i = 0; i < seeds.size(); ++i) {
        if (i == 8 && seeds.size() > 10) return s + fmt::format(", ... ({} seeds)", seeds.size());
        if (i) s += ',';
        s += std::to_string(seeds[i]);
    }
    return s;
}

// ---- The plan file ----
struct ShardPlan {
    std::string sceneFile;
    std::vector<std::string> sets;
    std::string scene;     // the document after the overrides
    std::string settings;  // resolvedSettings
    uint32_t shards = 0;
    uint64_t sppPerShard = 0;
    double timePerShard = 0.0;
    uint32_t baseSeed = 0;
    DerivativeCli derivative;  // key empty: radiance

    std::string checkpoint(const std::string& dir, uint32_t i) const {
        return (fs::path(dir) / fmt::format("shard-{}.checkpoint", i)).string();
    }
    std::string exr(const std::string& dir, uint32_t i) const {
        return (fs::path(dir) / fmt::format("shard-{}.exr", i)).string();
    }
};

std::string planPath(const std::string& dir) { return (fs::path(dir) / "shards.json").string(); }

ShardPlan readPlan(const std::string& dir) {
    const std::string path = planPath(dir);
    std::ifstream in(path);
    if (!in) throw InputError(path, "", "cannot open the shard plan (made by 'telescope shard')");
    nlohmann::json j = nlohmann::json::parse(in, nullptr, false);
    if (j.is_discarded() || !j.is_object()) throw InputError(path, "", "not a shard plan (not a JSON object)");
    ShardPlan p;
    try {
        if (j.at("format").get<std::string>() != "telescope-shards-1")
            throw InputError(path, "format", "not a shard plan of this version");
        p.sceneFile = j.at("scene_file").get<std::string>();
        p.sets = j.at("sets").get<std::vector<std::string>>();
        p.scene = j.at("scene").dump();
        p.settings = j.at("settings").dump();
        p.shards = j.at("shards").get<uint32_t>();
        p.sppPerShard = j.at("spp_per_shard").get<uint64_t>();
        p.timePerShard = j.at("time_per_shard").get<double>();
        p.baseSeed = j.at("base_seed").get<uint32_t>();
        if (j.contains("derivative")) {
            const auto& d = j.at("derivative");
            p.derivative.key = d.at("key").get<std::string>();
            if (!d.at("step").is_null()) p.derivative.step = d.at("step").get<double>();
            p.derivative.estimator = d.at("estimator").get<std::string>();
            p.derivative.levels = d.at("levels").get<uint32_t>();
            p.derivative.pmf = d.at("pmf").get<std::string>();
        }
    } catch (const nlohmann::json::exception& e) {
        throw InputError(path, "", fmt::format("not a shard plan: {}", e.what()));
    }
    if (p.shards == 0 || (p.sppPerShard == 0) == (p.timePerShard <= 0.0))
        throw InputError(path, "shards", "a plan needs shards and either spp_per_shard or time_per_shard");
    return p;
}

}  // namespace

// ---- merge ----

MergedRender mergeCheckpointFiles(const std::vector<std::string>& paths) {
    if (paths.size() < 2) throw InputError("", "inputs", "merge needs at least two checkpoints");
    struct Part {
        std::string path;
        CheckpointHeader c;
    };
    // ---- Check every header first (cheap), then add the sums one file at a time ----
    std::vector<Part> parts;
    for (const auto& path : paths) {
        parts.push_back({path, readCheckpointHeader(path)});
        const Part& p = parts.back();
        const Part& first = parts.front();
        if (p.c.scene != first.c.scene)
            throw InputError(path, firstDifference(first.c.scene, p.c.scene),
                             fmt::format("renders another scene than {}", first.path));
        if (p.c.settings != first.c.settings) {
            if (p.c.settings.empty() || first.c.settings.empty())
                throw InputError(path, "", fmt::format("{} records no settings (an older checkpoint); cannot check that "
                                                       "it was rendered with the settings of {}",
                                                       p.c.settings.empty() ? path : first.path,
                                                       p.c.settings.empty() ? first.path : path));
            throw InputError(path, firstDifference(first.c.settings, p.c.settings),
                             fmt::format("was rendered with other settings than {}", first.path));
        }
        if (p.c.estimator != first.c.estimator)
            throw InputError(path, "", fmt::format("was rendered with another estimator than {} ('{}' vs '{}')",
                                                   first.path, p.c.estimator, first.c.estimator));
        if (p.c.width != first.c.width || p.c.height != first.c.height)
            throw InputError(path, "", fmt::format("has another image size than {}", first.path));
        if (p.c.perPixelCounts != first.c.perPixelCounts)
            throw InputError(path, "", fmt::format("counts samples per pixel unlike {}", first.path));
        for (size_t i = 0; i + 1 < parts.size(); ++i)
            for (uint32_t s : p.c.seeds)
                if (std::find(parts[i].c.seeds.begin(), parts[i].c.seeds.end(), s) != parts[i].c.seeds.end())
                    throw InputError(path, "", fmt::format("has the same seed ({}) as {}: its samples are not independent",
                                                           s, parts[i].path));
    }
    // Seeds are disjoint, so ordering by the smallest seed is a total order: the sums do not
    // depend on the order of the arguments.
    std::sort(parts.begin(), parts.end(), [](const Part& a, const Part& b) {
        return *std::min_element(a.c.seeds.begin(), a.c.seeds.end()) < *std::min_element(b.c.seeds.begin(), b.c.seeds.end());
    });
    MergedRender m;
    m.film = loadCheckpoint(parts.front().path).film;
    for (size_t i = 1; i < parts.size(); ++i) m.film.merge(loadCheckpoint(parts[i].path).film);
    m.scene = parts.front().c.scene;
    m.estimator = parts.front().c.estimator;
    m.settings = parts.front().c.settings;
    for (const auto& p : parts)
        if (p.c.pendingUnits > 0)
            m.blocksLeftOut.push_back(blockLeftOut(
                p.path, pendingBlockText(p.c.samplesPerPixel, p.c.pendingLevel, p.c.pendingUnits, p.c.pendingUnitsTotal)));
    nlohmann::json shards = nlohmann::json::array();
    for (const auto& p : parts) {
        m.seeds.insert(m.seeds.end(), p.c.seeds.begin(), p.c.seeds.end());
        shards.push_back({{"file", p.path}, {"seeds", p.c.seeds}, {"spp", p.c.samplesPerPixel}});
    }
    std::sort(m.seeds.begin(), m.seeds.end());
    m.shards = shards.dump();
    return m;
}

namespace {

void writeMerged(const ImageOutputOptions& output, const MergedRender& m, bool quiet, size_t parts) {
    OutputInfo info{"merged", m.scene, m.estimator, "merged", m.settings, m.seeds.front(), 0.0, m.seeds, m.shards};
    writeImages(output, m.film, info);
    for (const auto& note : m.blocksLeftOut) fmt::print(stderr, "telescope: warning: {}\n", note);  // even with -q
    if (!quiet)
        fmt::print(stderr, "wrote {} ({} spp from {} renders, seeds {})\n", output.exrPath, m.film.samplesPerPixel(),
                   parts, seedList(m.seeds));
}

}  // namespace

int runMerge(const MergeOptions& optionsIn) {
    MergeOptions o = optionsIn;
    if (o.inputs.size() < 2) throw InputError("", "inputs", "merge needs at least two checkpoints");
    checkImageOutputs(o.output);
    MergedRender m = mergeCheckpointFiles(o.inputs);
    writeMerged(o.output, m, o.quiet, o.inputs.size());
    return 0;
}

// ---- shard: the plan ----

int runShardPlan(const CommonOptions& common, const ShardPlanOptions& o) {
    if (o.shards == 0) throw InputError("", "--shards", "at least one shard");
    if ((o.sppPerShard == 0) == (o.timePerShard <= 0.0))
        throw InputError("", "--spp-per-shard", "give either --spp-per-shard or --time-per-shard");
    if (uint64_t(o.seed) + o.shards - 1 > UINT32_MAX)
        throw InputError("", "--seed", fmt::format("seeds {} + 0..{} do not fit in 32 bits", o.seed, o.shards - 1));
    if (o.outDir.empty()) throw InputError("", "-o", "an output directory is required");
    Scene scene = loadWithOverrides(common);
    if (const char* key = autoPmfKey(scene.integrator); *key)
        throw InputError(scene.path, key,
                         "pmf \"auto\" would let every shard pick its own pmf, and shards of other settings do not "
                         "merge: put a pmf in the scene ('telescope render' prints the one its pilot picks)");
    if (!o.derivative.key.empty() && derivativeSettings(o.derivative).autoPmf)
        throw InputError("", "--derivative-pmf", "pmf \"auto\" would let every shard pick its own pmf, and shards of "
                                                 "other estimators do not merge: give the pmf ('telescope plan "
                                                 "--derivative' prints the one its pilot picks)");
    fs::path dir(o.outDir);
    fs::path parent = dir.parent_path().empty() ? fs::path(".") : dir.parent_path();
    if (!fs::is_directory(parent))
        throw InputError("", "-o", fmt::format("directory '{}' does not exist", parent.string()));
    if (fs::exists(planPath(o.outDir)))
        throw InputError(planPath(o.outDir), "", "already holds a shard plan: use another directory");
    fs::create_directories(dir);

    nlohmann::json j;
    j["format"] = "telescope-shards-1";
    j["scene_file"] = fs::absolute(common.scenePath).lexically_normal().string();
    j["sets"] = common.sets;
    j["scene"] = scene.document;
    j["settings"] = resolvedSettings(scene);
    j["shards"] = o.shards;
    j["spp_per_shard"] = o.sppPerShard;
    j["time_per_shard"] = o.timePerShard;
    j["base_seed"] = o.seed;
    j["seeds"] = fmt::format("{} + task id (0..{})", o.seed, o.shards - 1);
    if (!o.derivative.key.empty()) {
        const DerivativeCli& d = o.derivative;
        j["derivative"] = {{"key", d.key},
                           {"step", std::isnan(d.step) ? nlohmann::json() : nlohmann::json(d.step)},
                           {"estimator", d.estimator},
                           {"levels", d.levels},
                           {"pmf", d.pmf}};
    }
    writeTextAtomically(planPath(o.outDir), j.dump(2) + "\n");
    const std::string budget =
        o.sppPerShard ? fmt::format("{} spp", o.sppPerShard) : fmt::format("{} s", o.timePerShard);
    if (!common.quiet)
        fmt::print(stderr,
                   "wrote {}: {} shards of {}, seeds {}..{}\n"
                   "Slurm:   tools/slurm/submit {} OUT.exr   (an array of {} tasks and a dependent merge)\n"
                   "locally: for i in $(seq 0 {}); do telescope shard-render {} --task $i; done; "
                   "telescope shard-merge {} -o OUT.exr\n",
                   planPath(o.outDir), o.shards, budget, o.seed, o.seed + o.shards - 1, o.outDir, o.shards,
                   o.shards - 1, o.outDir, o.outDir);
    return 0;
}

// ---- shard-render: one task ----

int runShardRender(const CommonOptions& commonIn, const ShardRenderOptions& o) {
    ShardPlan plan = readPlan(o.dir);
    int task = o.task;
    if (task < 0) {
        const char* env = std::getenv("SLURM_ARRAY_TASK_ID");
        if (!env) throw InputError("", "--task", "no --task and no SLURM_ARRAY_TASK_ID");
        char* end = nullptr;
        long v = std::strtol(env, &end, 10);
        if (!*env || *end || v < 0) throw InputError("", "SLURM_ARRAY_TASK_ID", fmt::format("'{}' is not a task id", env));
        task = int(std::min<long>(v, INT32_MAX));
    }
    if (uint32_t(task) >= plan.shards)
        throw InputError(planPath(o.dir), "shards", fmt::format("task {} is not one of the plan's {} shards", task, plan.shards));

    CommonOptions common = commonIn;
    common.scenePath = plan.sceneFile;
    common.sets = plan.sets;
    {
        Scene scene = loadWithOverrides(common);
        if (scene.document.dump() != plan.scene)
            throw InputError(plan.sceneFile, firstDifference(plan.scene, scene.document.dump()),
                             fmt::format("the scene changed since {} was made", planPath(o.dir)));
    }

    RenderOptions r;
    r.derivative = plan.derivative;
    r.output.exrPath = plan.exr(o.dir, uint32_t(task));
    r.output.noPng = true;
    r.output.checkpointPath = plan.checkpoint(o.dir, uint32_t(task));
    r.seed = plan.baseSeed + uint32_t(task);
    r.seedGiven = true;
    r.checkpointEvery = o.checkpointEvery;
    if (plan.sppPerShard) {
        uint64_t have = 0;
        if (fs::exists(r.output.checkpointPath)) {
            have = readCheckpointHeader(r.output.checkpointPath).samplesPerPixel;
            r.resumePath = r.output.checkpointPath;
        }
        if (have > plan.sppPerShard)
            throw InputError(r.output.checkpointPath, "", fmt::format("holds {} spp, more than the plan's {}", have,
                                                                      plan.sppPerShard));
        if (have == plan.sppPerShard) {
            if (!common.quiet)
                fmt::print(stderr, "shard {}: {} already holds {} spp: nothing to do\n", task, r.output.checkpointPath,
                           have);
            return 0;
        }
        if (have > 0 && !common.quiet)
            fmt::print(stderr, "shard {}: resuming {} at {} of {} spp\n", task, r.output.checkpointPath, have,
                       plan.sppPerShard);
        r.spp = plan.sppPerShard - have;
    } else {
        // A requeued time-limited shard resumes its checkpoint and renders its budget again.
        if (fs::exists(r.output.checkpointPath)) r.resumePath = r.output.checkpointPath;
        r.timeLimit = plan.timePerShard;
    }
    return runRender(common, r);
}

// ---- shard-merge: the dependent job ----

int runShardMerge(const ShardMergeOptions& optionsIn) {
    ShardMergeOptions o = optionsIn;
    ShardPlan plan = readPlan(o.dir);
    checkImageOutputs(o.output);
    std::vector<std::string> present, missing;
    for (uint32_t i = 0; i < plan.shards; ++i) {
        const std::string path = plan.checkpoint(o.dir, i);
        (fs::exists(path) ? present : missing).push_back(path);
    }
    if (!missing.empty() && (!o.allowMissing || present.empty())) {
        std::string list;
        for (size_t i = 0; i < missing.size() && i < 4; ++i) list += (i ? ", " : "") + missing[i];
        if (missing.size() > 4) list += fmt::format(" and {} more", missing.size() - 4);
        throw InputError(planPath(o.dir), "", fmt::format("{} of {} shards have no checkpoint: {}{}", missing.size(),
                                                          plan.shards, list,
                                                          o.allowMissing ? "" : " (--allow-missing merges the others)"));
    }
    // Every checkpoint must be the plan's: its scene, its settings and its own seed.
    for (const auto& path : present) {
        const CheckpointHeader c = readCheckpointHeader(path);
        const uint32_t task = uint32_t(std::stoul(fs::path(path).stem().string().substr(6)));
        if (c.scene != plan.scene)
            throw InputError(path, firstDifference(plan.scene, c.scene),
                             fmt::format("renders another scene than {}", planPath(o.dir)));
        // A derivative shard records its derivative's settings as run too (h_0, the level pmf: the
        // renderer resolves them); the plan holds the scene's settings and the derivative's options.
        const SettingsParts parts = splitDerivativeSettings(c.settings);
        if (parts.scene != plan.settings)
            throw InputError(path, firstDifference(plan.settings, parts.scene),
                             fmt::format("was rendered with other settings than {}", planPath(o.dir)));
        if (!plan.derivative.key.empty() &&
            (parts.derivative.is_null() || parts.derivative.value("key", "") != plan.derivative.key ||
             parts.derivative.value("estimator", "") != plan.derivative.estimator ||
             parts.derivative.value("levels", 0u) != plan.derivative.levels))
            throw InputError(path, "derivative",
                             fmt::format("is not a derivative render of '{}' with the estimator and levels of {}",
                                         plan.derivative.key, planPath(o.dir)));
        if (c.seeds != std::vector<uint32_t>{plan.baseSeed + task})
            throw InputError(path, "", fmt::format("holds seed(s) {}, not shard {}'s seed {}", seedList(c.seeds), task,
                                                   plan.baseSeed + task));
    }
    if (!missing.empty())
        fmt::print(stderr, "shard-merge: merging {} of {} shards; missing: {}\n", present.size(), plan.shards,
                   missing.size());
    MergedRender m;
    if (present.size() == 1) {
        Checkpoint c = loadCheckpoint(present.front());
        m = MergedRender{c.film, c.scene, c.estimator, c.settings, c.seeds,
                         nlohmann::json::array({{{"file", present.front()}, {"seeds", c.seeds},
                                                 {"spp", c.film.samplesPerPixel()}}})
                             .dump()};
        const PendingSamples& block = c.film.pending();
        if (block.unitsDone > 0)
            m.blocksLeftOut.push_back(blockLeftOut(
                present.front(), pendingBlockText(c.film.samplesPerPixel(), block.level, block.unitsDone, block.unitsTotal)));
        m.film.setPending({});
    } else {
        m = mergeCheckpointFiles(present);
    }
    writeMerged(o.output, m, o.quiet, present.size());
    return 0;
}

}  // namespace telescope::cli
