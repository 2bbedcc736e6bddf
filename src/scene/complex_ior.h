// Named conductors for "conductor" and "rough_conductor" (complex_ior.cpp).
#pragma once

#include <string_view>
#include <vector>

#include <glm/glm.hpp>

namespace telescope {

struct ComplexIor {
    std::string_view name;
    glm::vec3 eta;
    glm::vec3 k;
};

// nullptr when Tungsten knows no material of that name.
const ComplexIor* findComplexIor(std::string_view name);
std::vector<std::string_view> complexIorNames();

}  // namespace telescope
