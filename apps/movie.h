#pragma once
/// `render --frames A:B --movie OUT` (issue 36): the frames, tone-mapped as the PNG previews, are
/// encoded into a movie by ffmpeg, a program of its own (Debian's `ffmpeg`), run without a shell.

#include <string>

namespace scatterlab::cli {

/// ffmpeg's container for a --movie path by its extension (.mp4, .mkv, .mov, .webm, .gif), or ""
/// when the extension is none of them.
std::string movieFormat(const std::string& path);

/// The ffmpeg --movie runs: $SCATTERLAB_FFMPEG when set (a path), else `ffmpeg` on PATH. Throws
/// ConfigError saying what was looked for when it is not an executable file.
std::string findFfmpeg();

/// Encodes the `count` PNGs `dir`/frame000000.png … at `fps` frames per second into `out` (in
/// container `format`, movieFormat()'s: H.264 for mp4/mkv/mov, VP9 for webm), odd image sizes
/// padded to even for the codecs. Throws IoError naming ffmpeg's exit status and the end of its
/// messages when it fails; `out` may then hold anything (the caller writes it as a temporary).
void encodeMovie(const std::string& ffmpeg, const std::string& dir, int count, double fps,
                 const std::string& format, const std::string& out);

/// A directory of its own under the system's temporary directory (mkdtemp), removed with what
/// it holds when the object dies. Throws IoError when it cannot be made.
class TempDir {
 public:
  explicit TempDir(const std::string& prefix);
  ~TempDir();
  TempDir(const TempDir&) = delete;
  TempDir& operator=(const TempDir&) = delete;
  const std::string& path() const { return path_; }

 private:
  std::string path_;
};

/// The name of frame `index` (0, 1, …) in encodeMovie's directory.
std::string movieFramePath(const std::string& dir, int index);

}  // namespace scatterlab::cli
