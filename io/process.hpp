// Facts about this machine and this process that memory budgets are drawn
// from (Linux: sysconf and /proc/self/status).
#pragma once

#include <cstddef>

namespace iso {

// Physical memory in bytes; 0 if unknown (callers choose their fallback).
std::size_t physical_memory_bytes();

// A field of /proc/self/status given in kB ("VmHWM:" the peak resident size,
// "VmSize:" the address space), in bytes; 0 if unknown.
std::size_t process_status_bytes(const char* field);

} // namespace iso
