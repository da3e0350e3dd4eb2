// Working memory kept between frames must not be reallocated to an exact fit whenever a frame needs a little more
// than the last one: std::vector::resize from a small size (after a smaller frame: a GPU frame's few survivors
// between CPU frames, a scene whose contact region grows) allocates exactly the new size, and every such fresh
// buffer costs a page fault per 4 KiB on first touch (about a thousand per frame for a 60,000-triangle box tree:
// milliseconds on the frame's critical path, and contended on many cores). These allocate with room to grow, so a
// buffer is reallocated O(log n) times over a run whatever the order of frame sizes, and a scene growing slowly
// touches only its new pages.
#pragma once

#include <algorithm>
#include <cstddef>
#include <vector>

namespace cullide {

/// Makes room for `n` elements: nothing when the capacity suffices, else for 1.5 times n (and at least 1.5 times the
/// old capacity). The room beyond what a frame writes is address space only: its pages are not touched, so they
/// cost no memory, and the next frames grow into them without a reallocation.
template <class T, class A>
void reserveGrowing(std::vector<T, A>& v, std::size_t n) {
    if (n > v.capacity()) v.reserve(std::max(n + n / 2, v.capacity() + v.capacity() / 2));
}

/// v.resize(n), growing the capacity geometrically (reserveGrowing).
template <class T, class A>
void resizeKeeping(std::vector<T, A>& v, std::size_t n) {
    reserveGrowing(v, n);
    v.resize(n);
}

/// v.assign(n, value), growing the capacity geometrically (reserveGrowing).
template <class T, class A>
void assignKeeping(std::vector<T, A>& v, std::size_t n, const T& value) {
    reserveGrowing(v, n);
    v.assign(n, value);
}

/// v.assign(first, last) for random-access iterators, growing the capacity geometrically (reserveGrowing).
template <class T, class A, class It>
void assignKeeping(std::vector<T, A>& v, It first, It last) {
    reserveGrowing(v, static_cast<std::size_t>(last - first));
    v.assign(first, last);
}

/// `lists` becomes `n` empty lists, each keeping its capacity (assign(n, {}) would free every one of them).
template <class T, class A, class B>
void clearLists(std::vector<std::vector<T, A>, B>& lists, std::size_t n) {
    lists.resize(n);
    for (auto& list : lists) list.clear();
}

}  // namespace cullide
