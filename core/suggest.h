#pragma once
/// Did-you-mean for misspelled names (methods, backends, scene keys, tool options): the one
/// place that decides what counts as a likely typo, so every message suggests alike.

#include <string>
#include <string_view>
#include <vector>

namespace scatterlab {

/// Edit distance between `a` and `b`: insertions, deletions, substitutions and swaps of two
/// neighbouring characters each cost 1 (optimal string alignment); case-sensitive.
std::size_t editDistance(std::string_view a, std::string_view b);

/// The candidate `word` most likely misspells, or "" when none is close: compared without
/// case, a candidate within max(1, |word| / 3) edits (so "GPU" -> "gpu", "per-voxle" ->
/// "per-voxel", but "cuda" suggests nothing among cpu, gpu, auto). The first of equally close
/// candidates wins; `word` itself is never suggested.
std::string closestMatch(std::string_view word, const std::vector<std::string>& candidates);

/// " (did you mean 'X'?)" for closestMatch's X, or "" when it has none; for messages of the
/// form "unknown method 'per-voxle' (did you mean 'per-voxel'?); allowed: ...".
std::string didYouMean(std::string_view word, const std::vector<std::string>& candidates);

}  // namespace scatterlab
