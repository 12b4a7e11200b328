// Dynamic sampling's error groups (scatterlab::errorBin, sampling/dynamic_sampling.h): the
// group of an error E above the threshold is its float's bits above the lowest
// SL_ERROR_BIN_SHIFT counted from the threshold's, clamped to [0, SL_ERROR_BINS − 1] (shared
// constants of core/stages.h, floats). The threshold is the double the SL_THRESHOLD pass left,
// rounded to float as the CPU rounds it.
const int kErrorBins = int(SL_ERROR_BINS);
int errorGroup(float e, double threshold) {
  uint shift = uint(SL_ERROR_BIN_SHIFT);
  int k = int(floatBitsToUint(e) >> shift);
  int t = int(floatBitsToUint(float(threshold)) >> shift);
  return clamp(k - t, 0, kErrorBins - 1);
}
