// Large buffers that are filled once (a scene file read whole, a scene's arrays) fault in a page
// at a time; with 4 KB pages an 80 MB file costs 20,000 faults, most of its read time on a VM.
#pragma once

#include <cstddef>

namespace flashgs {

// Asks the kernel for 2 MB pages over the 2 MB-aligned part of [begin, begin + bytes), memory
// not yet touched (Linux transparent huge pages in "madvise" mode; a no-op elsewhere or below
// a few MB). Only a hint: the contents and their lifetime are the caller's as before.
void advise_huge_pages(const void* begin, std::size_t bytes);

}  // namespace flashgs
