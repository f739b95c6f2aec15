// A shared library that is not a tripodal plugin: it exports no entry point.
extern "C" __attribute__((visibility("default"))) int unrelated_function() noexcept {
  return 42;
}
