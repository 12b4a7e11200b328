#pragma once
/// Tests that read the real data in ../shared/data (SCATTERLAB_SHARED_DATA) skip with a reason
/// when a clone has no shared data checkout beside it; CI has it.

#include <gtest/gtest.h>

#include <filesystem>

/// First statement of a test that reads SCATTERLAB_SHARED_DATA.
#define SCATTERLAB_REQUIRE_SHARED_DATA()                                                   \
  do {                                                                                     \
    if (!std::filesystem::is_directory(SCATTERLAB_SHARED_DATA))                            \
      GTEST_SKIP() << "needs the shared data directory " SCATTERLAB_SHARED_DATA            \
                      " (a checkout of the project's data beside the repository); absent " \
                      "here";                                                              \
  } while (0)
