// The positive control of the sanitizer runs: a leak that LeakSanitizer must report under
// .ci/sanitize's options (CTest passes this test only when the report names it).
#include <cstdlib>

int main() {
  void* volatile leaked = std::malloc(77);
  leaked = nullptr;
  return leaked != nullptr;
}
