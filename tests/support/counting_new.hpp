// Replaces the global allocation functions with counting ones, so a test can prove that a hot
// path allocates nothing. Include it in exactly one source file of a dedicated test executable:
// the replacement is program-wide.
//
// Every replaceable form that pairs with the ones below is replaced (plain, array, nothrow, sized
// deletes), all on malloc/free: under AddressSanitizer a form left out would come from the
// sanitizer's own allocator and be reported as an alloc-dealloc mismatch when our delete frees it.
#pragma once

#include <atomic>
#include <cstddef>
#include <cstdlib>
#include <new>

namespace tripodal::test {
inline std::atomic<std::size_t> g_allocations{0};
inline thread_local std::size_t t_allocations = 0;
/// Heap allocations made through operator new since the program started.
inline std::size_t allocations() noexcept { return g_allocations.load(std::memory_order_relaxed); }
/// Those made by the calling thread (a loop's own thread, counted while others allocate freely).
inline std::size_t thread_allocations() noexcept {
  return t_allocations;
}
}  // namespace tripodal::test

namespace tripodal::test::detail {
inline void* counted_malloc(std::size_t size) noexcept {
  g_allocations.fetch_add(1, std::memory_order_relaxed);
  ++t_allocations;
  return std::malloc(size == 0 ? 1 : size);
}
}  // namespace tripodal::test::detail

void* operator new(std::size_t size) {
  if (void* p = tripodal::test::detail::counted_malloc(size)) return p;
  throw std::bad_alloc();
}
void* operator new[](std::size_t size) {
  if (void* p = tripodal::test::detail::counted_malloc(size)) return p;
  throw std::bad_alloc();
}
void* operator new(std::size_t size, const std::nothrow_t&) noexcept {
  return tripodal::test::detail::counted_malloc(size);
}
void* operator new[](std::size_t size, const std::nothrow_t&) noexcept {
  return tripodal::test::detail::counted_malloc(size);
}
void operator delete(void* p) noexcept { std::free(p); }
void operator delete[](void* p) noexcept { std::free(p); }
void operator delete(void* p, std::size_t) noexcept { std::free(p); }
void operator delete[](void* p, std::size_t) noexcept { std::free(p); }
void operator delete(void* p, const std::nothrow_t&) noexcept { std::free(p); }
void operator delete[](void* p, const std::nothrow_t&) noexcept { std::free(p); }
