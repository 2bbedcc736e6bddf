// Error types shared by the whole program.
//
// InputError is bad input (a scene file, a command-line value): the CLI prints its one-line
// message and exits with code 2. Everything else that is thrown is a runtime failure (exit 1).
#pragma once

#include <stdexcept>
#include <string>

namespace telescope {

class InputError : public std::runtime_error {
public:
    // file: the file at fault ("" for the command line); key: a JSON path such as
    // "primitives[3].transform.scale" ("" when the whole file is at fault).
    InputError(std::string file, std::string key, const std::string& what)
        : std::runtime_error(format(file, key, what)), file_(std::move(file)), key_(std::move(key)) {}

    const std::string& file() const { return file_; }
    const std::string& key() const { return key_; }

private:
    static std::string format(const std::string& file, const std::string& key, const std::string& what) {
        std::string s = file.empty() ? std::string("command line") : file;
        if (!key.empty()) s += ": " + key;
        return s + ": " + what;
    }
    std::string file_, key_;
};

}  // namespace telescope
