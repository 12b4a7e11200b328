#pragma once
/// Typed exceptions. The library never exits on bad input; it throws one of these and apps/
/// turns it into a message and a non-zero exit code.

#include <stdexcept>
#include <string>

namespace scatterlab {

/// Base of every scatterlab error.
class Error : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// A scene or configuration value is missing, unknown, of the wrong type or out of range.
/// The message names the key (as a dotted path), the value and what is allowed.
class ConfigError : public Error {
 public:
  using Error::Error;
};

/// A valid scene that the chosen method cannot render by its nature, not a mistake in the
/// configuration (radial-blur with a light behind the camera, or inside the medium). The CLI
/// treats it as a ConfigError; an experiment records the run as "refused" with the reason and
/// counts it apart from failures (docs/harness.md).
class UnsupportedSceneError : public ConfigError {
 public:
  using ConfigError::ConfigError;
};

/// A file could not be read or written, or its contents are malformed.
class IoError : public Error {
 public:
  using Error::Error;
};

/// A request that is valid but asks for more than the library will do (memory bound, ...).
class LimitError : public Error {
 public:
  using Error::Error;
};

/// The GPU backend is unavailable or a GL operation failed.
class GpuError : public Error {
 public:
  using Error::Error;
};

}  // namespace scatterlab
