// The probe of lavapipe's loop cap (shared/gpu_types.h "Lavapipe's loop cap"; GLSL only). Once
// the cap is reached every loop of the invocation ends after one iteration, so a loop of `two`
// iterations (2, from a value the compiler cannot know, so that it stays a loop) runs once.
// Entry points call it after their work and count the lanes for which it says so.
bool loopCapReached(uint two) {
    uint n = 0u;
    for (uint i = 0u; i < two; ++i) ++n;
    return n != two;
}
