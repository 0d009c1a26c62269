// KINCAL_CHECK: for programming errors only (an invariant of kincal's own code broken).
// Bad outside data and device failures are Status values (kincal/status.h), never checks.
#pragma once

#include <cstdio>
#include <cstdlib>

#define KINCAL_CHECK(condition, message)                                                    \
  do {                                                                                      \
    if (!(condition)) {                                                                     \
      std::fprintf(stderr, "%s:%d: check failed: %s: %s\n", __FILE__, __LINE__, #condition, \
                   message);                                                                \
      std::abort();                                                                         \
    }                                                                                       \
  } while (false)
