// The --set engine: a dotted key path becomes a JSON pointer, walked with the checks the messages
// need (an index into a non-array, an index out of range, a member of a non-object).
#include "scene/scene_overrides.h"

#include <algorithm>

#include <fmt/format.h>

#include "core/error.h"

namespace telescope {

using nlohmann::json;

SceneOverride parseOverride(const std::string& text) {
    const size_t eq = text.find('=');
    if (eq == std::string::npos) throw InputError("", "", fmt::format("--set '{}': expected key=value", text));
    SceneOverride o{text.substr(0, eq), text.substr(eq + 1)};
    if (o.key.empty()) throw InputError("", "", fmt::format("--set '{}': the key before '=' is empty", text));
    return o;
}

namespace {

struct KeyToken {
    bool isIndex = false;
    std::string name;  // a member name, or the index in decimal
};

// Splits "primitives[2].bsdf" into primitives, [2], bsdf.
std::vector<KeyToken> parseKeyPath(const std::string& key, const std::string& sceneName) {
    auto malformed = [&](const std::string& why) {
        throw InputError("", key, fmt::format("malformed --set key path for {}: {}", sceneName, why));
    };
    std::vector<KeyToken> tokens;
    size_t i = 0;
    while (true) {
        const size_t start = i;
        while (i < key.size() && key[i] != '.' && key[i] != '[' && key[i] != ']') ++i;
        if (i == start) malformed("empty name");
        tokens.push_back({false, key.substr(start, i - start)});
        while (i < key.size() && key[i] == '[') {
            const size_t close = key.find(']', i);
            if (close == std::string::npos) malformed("missing ']'");
            const std::string digits = key.substr(i + 1, close - i - 1);
            if (digits.empty() || digits.size() > 9 ||
                !std::all_of(digits.begin(), digits.end(), [](char c) { return c >= '0' && c <= '9'; }))
                malformed("index '" + digits + "' is not a non-negative integer");
            tokens.push_back({true, std::to_string(std::stoul(digits))});
            i = close + 1;
        }
        if (i == key.size()) return tokens;
        if (key[i] != '.') malformed(fmt::format("unexpected '{}'", key[i]));
        ++i;
    }
}

}  // namespace

json::json_pointer overridePointer(const std::string& key, const std::string& sceneName) {
    json::json_pointer pointer;
    for (const KeyToken& t : parseKeyPath(key, sceneName)) pointer.push_back(t.name);
    return pointer;
}

void applyOverride(json& doc, const SceneOverride& o, const std::string& sceneName) {
    // The key and a bare-string value enter the document, which must stay valid UTF-8 to be
    // written out (fuzz/regressions/set-value-invalid-utf8.bin).
    try {
        (void)json(o.key + o.value).dump();
    } catch (const json::type_error&) {
        throw InputError("", "--set", fmt::format("the override of '{}' is not valid UTF-8 text",
                                                  json(o.key).dump(-1, ' ', false, json::error_handler_t::replace)));
    }
    json::json_pointer at;  // the part of the path walked so far
    std::string walked;     // the same, as a key path for messages
    for (const KeyToken& t : parseKeyPath(o.key, sceneName)) {
        json& node = doc[at];
        if (t.isIndex) {
            if (!node.is_array())
                throw InputError("", o.key, fmt::format("--set: '{}' in {} is not an array", walked, sceneName));
            if (std::stoul(t.name) >= node.size())
                throw InputError("", o.key,
                                 fmt::format("--set: index {} is out of range, '{}' in {} has {} elements", t.name,
                                             walked, sceneName, node.size()));
            walked += "[" + t.name + "]";
        } else {
            if (node.is_null()) node = json::object();
            if (!node.is_object())
                throw InputError("", o.key,
                                 fmt::format("--set: '{}' in {} is a {}, not an object", walked.empty() ? "(top level)" : walked,
                                             sceneName, node.type_name()));
            walked += (walked.empty() ? "" : ".") + t.name;
        }
        at.push_back(t.name);
    }
    json value = json::parse(o.value, nullptr, /*allow_exceptions=*/false);
    doc[at] = value.is_discarded() ? json(o.value) : std::move(value);
}

}  // namespace telescope
