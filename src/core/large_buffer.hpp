// Internal: the allocator of the loaders' large per-load arrays (the XML tree of a big net: tens of
// MB each, issue 42). Such an array is fresh memory every load (above glibc's mmap threshold), and
// its first touch costs one page fault per 4 KiB page: a third of a 100,000-place net's load went to
// the kernel. From 16 MiB on, the array is aligned to 2 MiB and offered to transparent huge pages
// (Linux madvise; a hint the kernel may decline), so a 2 MiB region faults once, and the tree
// takes fewer TLB entries while the readers walk it. Below that, and elsewhere, std::allocator.
#pragma once

#include <cstddef>
#include <memory>
#include <new>

#if defined(__linux__)
#include <sys/mman.h>
#endif

namespace tripodal::detail {

template <typename T>
class LargeBufferAllocator {
 public:
  using value_type = T;

  LargeBufferAllocator() noexcept = default;
  template <typename U>
  LargeBufferAllocator(const LargeBufferAllocator<U>& /*other*/) noexcept {}  // NOLINT(google-explicit-constructor): rebinding

  [[nodiscard]] T* allocate(std::size_t n) {
    if (!huge(n)) return std::allocator<T>().allocate(n);
    if (n > kMaxBytes / sizeof(T)) throw std::bad_array_new_length();
    const std::size_t bytes = rounded(n);
    void* p = ::operator new (bytes, std::align_val_t{kHugePage});
#if defined(__linux__) && defined(MADV_HUGEPAGE)
    (void)::madvise(p, bytes, MADV_HUGEPAGE);  // a hint: refused or unsupported, 4 KiB pages as before
#endif
    return static_cast<T*>(p);
  }
  void deallocate(T* p, std::size_t n) noexcept {
    if (!huge(n)) {
      std::allocator<T>().deallocate(p, n);
      return;
    }
    // Unsized: clang before 17 does not declare sized deallocation without -fsized-deallocation.
    ::operator delete (p, std::align_val_t{kHugePage});
  }

  template <typename U>
  bool operator==(const LargeBufferAllocator<U>& /*other*/) const noexcept {
    return true;
  }

 private:
  static constexpr std::size_t kHugePage = std::size_t{2} << 20;
  // Arrays below glibc's mmap ceiling (32 MiB) are, once freed, reused from the heap already
  // faulted in: only those near and above it are fresh memory every load.
  static constexpr std::size_t kHugeFrom = std::size_t{16} << 20;
  static constexpr std::size_t kMaxBytes = std::size_t{1} << 47;  // beyond any address space
  static constexpr bool huge(std::size_t n) noexcept {
    return n >= kHugeFrom / sizeof(T);
  }
  static constexpr std::size_t rounded(std::size_t n) noexcept {
    return (n * sizeof(T) + kHugePage - 1) / kHugePage * kHugePage;
  }
};

}  // namespace tripodal::detail
