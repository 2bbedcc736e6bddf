// A shared library with thread-local data, loaded with dlopen by threads_with_dynamic_tls.cpp:
// its thread_local lives in a dynamic TLS block that glibc allocates with malloc on each thread's
// first access. The pointer it holds is the only reference to its allocation.
namespace {
thread_local int* held = nullptr;
}

extern "C" void* telescope_touch_thread_local() {
  held = new int[16]();
  return static_cast<void*>(&held);
}
