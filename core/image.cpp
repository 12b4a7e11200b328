#include "core/image.h"

#include <IexBaseExc.h>
#include <ImfChannelList.h>
#include <ImfFrameBuffer.h>
#include <ImfHeader.h>
#include <ImfIO.h>
#include <ImfMatrixAttribute.h>
#include <ImfOutputFile.h>
#include <ImfStandardAttributes.h>
#include <ImfStringAttribute.h>
#include <openexr.h>
#include <png.h>

#include <algorithm>
#include <cerrno>
#include <climits>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <fstream>
#include <iterator>
#include <limits>

#include "core/atomic_file.h"
#include "core/error.h"
#include "core/limits.h"

namespace scatterlab {

namespace {

/// OpenEXR output into the checked stream of writeFileAtomically (OpenEXR's own StdOFStream
/// leaves the final flush of its std::ofstream unchecked).
class ExrOStream : public Imf::OStream {
 public:
  ExrOStream(std::ostream& os, const std::string& name) : Imf::OStream(name.c_str()), os_(os) {}
  void write(const char c[], int n) override {
    errno = 0;
    if (!os_.write(c, n)) failed("write");
    pos_ += uint64_t(n);
  }
  // Never throws: ~OutputFile calls it outside its try block. After a failed write (a full
  // disk) the stream has no position, and OpenEXR said "Cannot determine current file
  // position" (issue 37); the position is kept here, and the write's own error is reported.
  uint64_t tellp() override {
    const std::streampos p = os_.tellp();
    return p < 0 ? pos_ : uint64_t(p);
  }
  void seekp(uint64_t pos) override {
    errno = 0;
    if (!os_.seekp(std::streamoff(pos))) failed("seek");
    pos_ = pos;
  }

 private:
  // Iex::IoExc, not IoError: OpenEXR's destructors (which write the offset table) catch only
  // Iex's exceptions, and any other one escaping them ends the process (std::terminate). The
  // writer's catch turns it into an IoError naming the file.
  [[noreturn]] static void failed(const char* what) {
    const int e = errno;
    throw Iex::IoExc(std::string(what) + " failed" +
                     (e == ENOSPC ? std::string(": no space left on the device")
                      : e != 0    ? ": " + std::string(std::strerror(e))
                                  : std::string()));
  }
  uint64_t pos_ = 0;
  std::ostream& os_;
};

}  // namespace

void writeExr(const Image& img, const std::string& path, const ExrAttributes& attributes) {
  if (img.width() <= 0 || img.height() <= 0) throw IoError("cannot write an empty image");
  const bool hasAlpha = !img.alpha().empty(), hasDepth = !img.depth().empty();
  for (const auto& [name, values] :
       {std::pair<const char*, const std::vector<float>*>{"alpha", &img.alpha()},
        {"depth", &img.depth()}})
    if (!values->empty() && values->size() != img.pixels().size())
      throw IoError("cannot write EXR '" + path + "': " + name + " has " +
                    std::to_string(values->size()) + " values for " +
                    std::to_string(img.pixels().size()) + " pixels");
  writeFileAtomically(path, [&](std::ostream& os) {
    try {
      Imf::Header header(img.width(), img.height());
      for (const char* c : {"R", "G", "B"}) header.channels().insert(c, Imf::Channel(Imf::FLOAT));
      if (hasAlpha) header.channels().insert("A", Imf::Channel(Imf::FLOAT));
      if (hasDepth) header.channels().insert("Z", Imf::Channel(Imf::FLOAT));
      // The colour space, for compositors and viewers: scatterlab's RGB is linear with the
      // Rec. 709 / sRGB primaries and D65 white, which is what Imf::Chromaticities() holds.
      Imf::addChromaticities(header, Imf::Chromaticities());
      for (const auto& [name, value] : attributes.strings)
        header.insert(name, Imf::StringAttribute(value));
      for (const auto& [name, m] : attributes.matrices)
        header.insert(name, Imf::M44fAttribute(Imath::M44f(m[0], m[1], m[2], m[3], m[4], m[5], m[6],
                                                           m[7], m[8], m[9], m[10], m[11], m[12],
                                                           m[13], m[14], m[15])));
      ExrOStream stream(os, path);
      Imf::OutputFile file(stream, header);
      Imf::FrameBuffer fb;
      char* base = const_cast<char*>(reinterpret_cast<const char*>(img.pixels().data()));
      const size_t xs = sizeof(Vec3), ys = sizeof(Vec3) * img.width();
      fb.insert("R", Imf::Slice(Imf::FLOAT, base, xs, ys));
      fb.insert("G", Imf::Slice(Imf::FLOAT, base + sizeof(float), xs, ys));
      fb.insert("B", Imf::Slice(Imf::FLOAT, base + 2 * sizeof(float), xs, ys));
      const auto scalar = [&](const std::vector<float>& v) {
        return Imf::Slice(Imf::FLOAT, const_cast<char*>(reinterpret_cast<const char*>(v.data())),
                          sizeof(float), sizeof(float) * img.width());
      };
      if (hasAlpha) fb.insert("A", scalar(img.alpha()));
      if (hasDepth) fb.insert("Z", scalar(img.depth()));
      file.setFrameBuffer(fb);
      file.writePixels(img.height());
    } catch (const std::exception& e) {
      throw IoError("cannot write EXR '" + path + "': " + e.what());
    }
  });
}

namespace {

/// Walks the EXR header(s) before OpenEXR reads them: every attribute (name, type, int32 size)
/// must lie inside the file. OpenEXR allocates an attribute's announced size before reading it
/// (fuzz_exr: a 721-byte file drove the RSS to 1.9 GB). Throws IoError naming the attribute.
void checkExrAttributeSizes(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  const std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  const std::size_t n = bytes.size();
  if (n < 8) return;  // OpenEXR reports the short file
  std::uint32_t version;
  std::memcpy(&version, bytes.data() + 4, 4);
  const bool multipart = (version & 0x1000u) != 0;
  std::size_t pos = 8;
  const auto cstring = [&](const char* what) {
    const std::size_t end = bytes.find('\0', pos);
    if (end == std::string::npos || end - pos > 255)
      throw IoError("header: " + std::string(what) + " at byte " + std::to_string(pos) +
                    " is not terminated within 256 bytes or the file");
    std::string v = bytes.substr(pos, end - pos);
    pos = end + 1;
    return v;
  };
  const auto printable = [](std::string t) {
    for (char& c : t)
      if (c < 0x20 || c > 0x7e) c = '?';
    return t;
  };
  for (;;) {  // headers (one unless multi-part), each a list of attributes ended by a NUL
    for (;;) {
      const std::string name = cstring("an attribute name");
      if (name.empty()) break;
      const std::string type = cstring("an attribute type");
      const std::string shown = "header: attribute '" + printable(name.substr(0, 40)) + "'";
      std::int32_t size;
      if (n - pos < 4) throw IoError(shown + " is truncated");
      std::memcpy(&size, bytes.data() + pos, 4);
      pos += 4;
      if (size < 0 || std::size_t(size) > n - pos)
        throw IoError(shown + " announces " + std::to_string(size) +
                      " bytes, beyond the end of the file (" + std::to_string(n) + " bytes)");
      // OpenEXR's C++ reader reads a known type by its own layout, not by the announced size
      // (a float is 4 bytes whatever the size says; a chlist runs to its empty name; a preview
      // allocates width x height x 4 bytes): where the two disagree it goes on from another
      // byte than this walk, and an attribute read from there can announce gigabytes
      // (fuzz_exr: a 308-byte file, 1.69 GB allocated). So the sizes of known types must be
      // their layouts' (true of every well-formed file).
      const std::size_t at = pos, end = pos + std::size_t(size);
      const auto expect = [&](std::size_t want) {
        if (std::size_t(size) != want)
          throw IoError(shown + " of type '" + printable(type.substr(0, 40)) + "' has " +
                        std::to_string(size) + " bytes; its layout has " + std::to_string(want));
      };
      const auto u32 = [&](std::size_t o) {
        std::uint32_t v;
        std::memcpy(&v, bytes.data() + o, 4);
        return v;
      };
      static const std::pair<const char*, std::size_t> kFixed[] = {
          {"box2i", 16},      {"box2f", 16},   {"chromaticities", 32},
          {"compression", 1}, {"double", 8},   {"envmap", 1},
          {"float", 4},       {"int", 4},      {"keycode", 28},
          {"lineOrder", 1},   {"m33f", 36},    {"m33d", 72},
          {"m44f", 64},       {"m44d", 128},   {"rational", 8},
          {"tiledesc", 9},    {"timecode", 8}, {"v2i", 8},
          {"v2f", 8},         {"v2d", 16},     {"v3i", 12},
          {"v3f", 12},        {"v3d", 24},     {"deepImageState", 1}};
      for (const auto& [t, bytesOf] : kFixed)
        if (type == t) expect(bytesOf);
      if (type == "preview") {
        if (size < 8) expect(8);
        expect(8 + std::size_t(u32(at)) * u32(at + 4) * 4);
      } else if (type == "chlist") {
        std::size_t q = at;  // entries: name, NUL, 16 bytes; then an empty name
        for (;;) {
          const std::size_t z = q < end ? bytes.find('\0', q) : std::string::npos;
          if (z == std::string::npos || z >= end)
            throw IoError(shown + " (a channel list) does not end within its " +
                          std::to_string(size) + " bytes");
          if (z == q) {
            q = z + 1;
            break;
          }
          q = z + 1 + 16;
        }
        expect(q - at);
      }
      pos = end;
    }
    if (!multipart || pos >= n || bytes[pos] == '\0') break;
  }
}

}  // namespace

namespace {

// The last message of OpenEXR's core for this thread (its default handler prints to stderr).
thread_local std::string exrCoreMessage;

/// An OpenEXR core read context, finished on every path.
class ExrReadContext {
 public:
  explicit ExrReadContext(const std::string& path) {
    exr_context_initializer_t init = EXR_DEFAULT_CONTEXT_INITIALIZER;
    init.error_handler_fn = [](exr_const_context_t, exr_result_t, const char* message) {
      exrCoreMessage = message ? message : "";
    };
    check(exr_start_read(&ctx_, path.c_str(), &init), "cannot parse the header");
  }
  ~ExrReadContext() {
    if (ctx_) exr_finish(&ctx_);
  }
  ExrReadContext(const ExrReadContext&) = delete;
  ExrReadContext& operator=(const ExrReadContext&) = delete;
  exr_context_t get() const { return ctx_; }

  /// Throws IoError(`what`: the core's message) unless `r` is EXR_ERR_SUCCESS.
  static void check(exr_result_t r, const std::string& what) {
    if (r == EXR_ERR_SUCCESS) return;
    std::string detail = exrCoreMessage.empty() ? exr_get_default_error_message(r) : exrCoreMessage;
    exrCoreMessage.clear();
    // The core prefixes its messages with the file's name, which the caller adds anyway.
    if (const std::size_t colon = detail.find(": ("); colon != std::string::npos)
      detail = detail.substr(colon + 2);
    throw IoError(what + ": " + detail);
  }

 private:
  exr_context_t ctx_ = nullptr;
};

/// One chunk's pixels of the channels R, G, B, A and Z, decoded by OpenEXR's core into `img`
/// (converted to float; other channels skipped). The core checks every chunk against the
/// offset table, its size against the lines it covers and the decompressed size against the
/// expected one: OpenEXR's C++ InputFile left pixels of empty or short chunks as whatever its
/// line buffer held (issue 37).
/// (x0, y0): the chunk's first pixel relative to the data window's origin (the core gives a
/// scanline chunk's first line but a tile's indices).
void decodeExrChunk(exr_context_t ctx, const exr_chunk_info_t& chunk, exr_decode_pipeline_t& d,
                    bool first, std::size_t x0, std::size_t y0, Image& img,
                    const std::string& where) {
  ExrReadContext::check(
      first ? exr_decoding_initialize(ctx, 0, &chunk, &d) : exr_decoding_update(ctx, 0, &chunk, &d),
      where);
  const std::size_t w = std::size_t(img.width());
  if (x0 + std::size_t(std::max(chunk.width, 0)) > w ||
      y0 + std::size_t(std::max(chunk.height, 0)) > std::size_t(img.height()))
    throw IoError(where + ": the chunk lies outside the data window");
  const std::size_t origin = y0 * w + x0;
  for (int c = 0; c < d.channel_count; ++c) {
    exr_coding_channel_info_t& ch = d.channels[c];
    const std::string name = ch.channel_name ? ch.channel_name : "";
    uint8_t* to = nullptr;
    int32_t stride = sizeof(float);
    if (name == "R" || name == "G" || name == "B") {
      to = reinterpret_cast<uint8_t*>(&img.pixels()[origin][name == "R" ? 0 : name == "G" ? 1 : 2]);
      stride = sizeof(Vec3);
    } else if (name == "A" && !img.alpha().empty()) {
      to = reinterpret_cast<uint8_t*>(img.alpha().data() + origin);
    } else if (name == "Z" && !img.depth().empty()) {
      to = reinterpret_cast<uint8_t*>(img.depth().data() + origin);
    }
    ch.decode_to_ptr = to;
    ch.user_pixel_stride = stride;
    ch.user_line_stride = int32_t(stride * w);
    ch.user_bytes_per_element = sizeof(float);
    ch.user_data_type = EXR_PIXEL_FLOAT;
  }
  ExrReadContext::check(exr_decoding_choose_default_routines(ctx, 0, &d), where);
  ExrReadContext::check(exr_decoding_run(ctx, 0, &d), where);
}

}  // namespace

Image readExr(const std::string& path) {
  checkReadableFile(path, "image");
  try {
    checkExrAttributeSizes(path);
    ExrReadContext file(path);
    exr_context_t ctx = file.get();
    exr_storage_t storage;
    ExrReadContext::check(exr_get_storage(ctx, 0, &storage), "cannot read the first part");
    if (storage != EXR_STORAGE_SCANLINE && storage != EXR_STORAGE_TILED)
      throw IoError("deep images are not supported (the first part holds deep data)");
    exr_attr_box2i_t dw;
    ExrReadContext::check(exr_get_data_window(ctx, 0, &dw), "no data window");
    // In 64 bits: a corrupt data window overflows int (fuzz_exr found a 40 GB allocation).
    const std::int64_t w64 = std::int64_t(dw.max.x) - dw.min.x + 1,
                       h64 = std::int64_t(dw.max.y) - dw.min.y + 1;
    if (w64 < 1 || h64 < 1 || w64 > INT_MAX || h64 > INT_MAX)
      throw IoError("invalid data window of " + std::to_string(w64) + "x" + std::to_string(h64) +
                    " pixels");
    const exr_attr_chlist_t* channels = nullptr;
    ExrReadContext::check(exr_get_channels(ctx, 0, &channels), "no channel list");
    bool rgb = false, alpha = false, depth = false;
    for (int i = 0; i < channels->num_channels; ++i) {
      const exr_attr_chlist_entry_t& e = channels->entries[i];
      const std::string name(e.name.str, std::size_t(std::max(e.name.length, 0)));
      const bool used = name == "R" || name == "G" || name == "B" || name == "A" || name == "Z";
      if (used && (e.x_sampling != 1 || e.y_sampling != 1))
        throw IoError("channel '" + name + "' is subsampled (" + std::to_string(e.x_sampling) +
                      "x" + std::to_string(e.y_sampling) + "); only full-resolution R, G, B, A " +
                      "and Z channels are read");
      rgb = rgb || name == "R" || name == "G" || name == "B";
      alpha = alpha || name == "A";
      depth = depth || name == "Z";
    }
    if (!rgb) throw IoError("no R, G or B channel");
    checkMemory(path, "an image of " + std::to_string(w64) + "x" + std::to_string(h64) + " pixels",
                double(w64) * double(h64) * double(sizeof(Vec3) + sizeof(float)));
    const int w = int(w64), h = int(h64);
    Image img(w, h);  // zero: a channel the file lacks reads as 0
    if (alpha) img.alpha().assign(std::size_t(w) * h, 0.0f);
    if (depth) img.depth().assign(std::size_t(w) * h, 0.0f);

    exr_decode_pipeline_t d{};  // all zero, as EXR_DECODE_PIPELINE_INITIALIZER ({0}) but warning-free
    struct Pipeline {
      exr_context_t ctx;
      exr_decode_pipeline_t& d;
      ~Pipeline() { exr_decoding_destroy(ctx, &d); }
    } pipeline{ctx, d};
    bool first = true;
    if (storage == EXR_STORAGE_SCANLINE) {
      int32_t lines = 0;
      ExrReadContext::check(exr_get_scanlines_per_chunk(ctx, 0, &lines), "no lines per chunk");
      for (std::int64_t y = dw.min.y; y <= dw.max.y; y += std::max(lines, 1)) {
        const std::string where = "line " + std::to_string(y) + " (data window lines " +
                                  std::to_string(dw.min.y) + " to " + std::to_string(dw.max.y) +
                                  ") has no valid pixel data";
        exr_chunk_info_t chunk;
        ExrReadContext::check(exr_read_scanline_chunk_info(ctx, 0, int(y), &chunk), where);
        decodeExrChunk(ctx, chunk, d, first, 0, std::size_t(chunk.start_y - dw.min.y), img, where);
        first = false;
      }
    } else {
      int32_t tileW = 0, tileH = 0;
      ExrReadContext::check(exr_get_tile_sizes(ctx, 0, 0, 0, &tileW, &tileH), "no tile size");
      if (tileW < 1 || tileH < 1)
        throw IoError("invalid tile size " + std::to_string(tileW) + "x" + std::to_string(tileH));
      const std::int64_t tilesX = (w64 + tileW - 1) / tileW, tilesY = (h64 + tileH - 1) / tileH;
      for (int ty = 0; ty < int(tilesY); ++ty)
        for (int tx = 0; tx < int(tilesX); ++tx) {
          const std::string where = "tile (" + std::to_string(tx) + ", " + std::to_string(ty) +
                                    ") has no valid pixel data";
          exr_chunk_info_t chunk;
          ExrReadContext::check(exr_read_tile_chunk_info(ctx, 0, tx, ty, 0, 0, &chunk), where);
          decodeExrChunk(ctx, chunk, d, first, std::size_t(tx) * tileW, std::size_t(ty) * tileH,
                         img, where);
          first = false;
        }
    }
    return img;
  } catch (const IoError& e) {
    throw IoError("cannot read EXR '" + path + "': " + e.what());
  } catch (const LimitError&) {
    throw;
  } catch (const std::bad_alloc&) {
    throw IoError("cannot read EXR '" + path + "': corrupt sizes (allocation failed)");
  } catch (const std::exception& e) {
    throw IoError("cannot read EXR '" + path + "': " + e.what());
  }
}

ExrAttributes readExrAttributes(const std::string& path) {
  checkReadableFile(path, "image");
  try {
    checkExrAttributeSizes(path);
    ExrReadContext file(path);
    exr_context_t ctx = file.get();
    int32_t count = 0;
    ExrReadContext::check(exr_get_attribute_count(ctx, 0, &count), "no attribute list");
    ExrAttributes a;
    for (int32_t i = 0; i < count; ++i) {
      const exr_attribute_t* attr = nullptr;
      ExrReadContext::check(exr_get_attribute_by_index(ctx, 0, EXR_ATTR_LIST_FILE_ORDER, i, &attr),
                            "cannot read attribute " + std::to_string(i));
      if (!attr || !attr->name) continue;
      if (attr->type == EXR_ATTR_STRING && attr->string && attr->string->str)
        a.strings.emplace_back(
            attr->name,
            std::string(attr->string->str, std::size_t(std::max(attr->string->length, 0))));
      else if (attr->type == EXR_ATTR_M44F && attr->m44f) {
        std::array<float, 16> m{};
        std::copy(attr->m44f->m, attr->m44f->m + 16, m.begin());
        a.matrices.emplace_back(attr->name, m);
      }
    }
    return a;
  } catch (const IoError& e) {
    throw IoError("cannot read EXR '" + path + "': " + e.what());
  } catch (const std::bad_alloc&) {
    throw IoError("cannot read EXR '" + path + "': corrupt sizes (allocation failed)");
  }
}

NonFiniteValues countNonFinite(const Image& img, bool withAlpha) {
  NonFiniteValues n;
  const std::vector<float>& alpha = img.alpha();
  const std::size_t count = img.pixels().size();
  for (std::size_t i = 0; i < count; ++i) {
    const Vec3& p = img.pixels()[i];
    bool bad = false;
    for (int c = 0; c < 4; ++c) {
      if (c == 3 && (!withAlpha || alpha.size() != count)) break;
      const float v = c < 3 ? p[c] : alpha[i];
      if (std::isnan(v)) {
        ++n.nan;
        bad = true;
      } else if (std::isinf(v)) {
        ++n.inf;
        bad = true;
      }
    }
    if (bad && n.x < 0) {
      n.x = int(i % std::size_t(img.width()));
      n.y = int(i / std::size_t(img.width()));
    }
  }
  return n;
}

std::string NonFiniteValues::describe() const {
  return std::to_string(nan + inf) + " non-finite channel value" + (nan + inf == 1 ? "" : "s") +
         " (" + std::to_string(nan) + " NaN, " + std::to_string(inf) +
         " inf; the first at pixel (" + std::to_string(x) + ", " + std::to_string(y) + "))";
}

float toneMapSrgb(float linear, float exposure) {
  float v = linear * std::exp2(exposure);
  if (!(v > 0.0f)) return 0.0f;  // also maps NaN to 0
  if (v >= 1.0f) return 1.0f;
  return v <= 0.0031308f ? 12.92f * v : 1.055f * std::pow(v, 1.0f / 2.4f) - 0.055f;
}

ToneCurve parseToneCurve(const std::string& name, const std::string& key) {
  if (name == "linear") return ToneCurve::Linear;
  if (name == "filmic") return ToneCurve::Filmic;
  if (name == "aces") return ToneCurve::Aces;
  throw ConfigError("'" + key + "': unknown tone curve '" + name +
                    "' (allowed: linear, filmic, aces)");
}

namespace {

/// Hable's filmic operator (Uncharted 2): shoulder 0.15, linear 0.50, angle 0.10, toe 0.20,
/// toe numerator 0.02, denominator 0.30.
float hable(float x) {
  const float A = 0.15f, B = 0.50f, C = 0.10f, D = 0.20f, E = 0.02f, F = 0.30f;
  return ((x * (A * x + C * B) + D * E) / (x * (A * x + B) + D * F)) - E / F;
}

}  // namespace

float toneCurve(float v, ToneCurve curve) {
  if (!(v > 0.0f)) return 0.0f;  // also maps NaN to 0
  switch (curve) {
    case ToneCurve::Linear:
      return std::min(v, 1.0f);
    case ToneCurve::Filmic: {
      constexpr float kWhite = 11.2f;
      return std::min(1.0f, hable(v) / hable(kWhite));
    }
    case ToneCurve::Aces:
      // Narkowicz 2015, "ACES Filmic Tone Mapping Curve".
      return std::clamp(v * (2.51f * v + 0.03f) / (v * (2.43f * v + 0.59f) + 0.14f), 0.0f, 1.0f);
  }
  return 0.0f;
}

void writePng(const Image& img, const std::string& path, float exposure, ToneCurve curve) {
  if (img.width() <= 0 || img.height() <= 0) throw IoError("cannot write an empty image");
  // NaN used to write an all-black PNG; beyond +-100 stops 2^exposure leaves single precision.
  if (!(std::abs(exposure) <= 100.0f))
    throw ConfigError("PNG exposure " + std::to_string(exposure) +
                      " is out of range; allowed: a number of stops in [-100, 100]");
  std::vector<unsigned char> buf(size_t(img.width()) * img.height() * 3);
  const float scale = std::exp2(exposure);
  for (size_t i = 0; i < img.pixels().size(); ++i)
    for (int c = 0; c < 3; ++c)
      buf[3 * i + c] = static_cast<unsigned char>(
          (curve == ToneCurve::Linear
               ? toneMapSrgb(img.pixels()[i][c], exposure)
               : toneMapSrgb(toneCurve(img.pixels()[i][c] * scale, curve), 0.0f)) *
              255.0f +
          0.5f);
  // Encoded in memory (libpng's simplified API), then written by the one checked writer.
  png_image pi;
  std::memset(&pi, 0, sizeof(pi));
  pi.version = PNG_IMAGE_VERSION;
  pi.width = img.width();
  pi.height = img.height();
  pi.format = PNG_FORMAT_RGB;
  png_alloc_size_t size = 0;
  if (!png_image_write_to_memory(&pi, nullptr, &size, 0, buf.data(), 0, nullptr))
    throw IoError("cannot write PNG '" + path + "': " + pi.message);
  std::string bytes(size, '\0');
  if (!png_image_write_to_memory(&pi, bytes.data(), &size, 0, buf.data(), 0, nullptr))
    throw IoError("cannot write PNG '" + path + "': " + pi.message);
  bytes.resize(size);
  writeBytesAtomically(path, bytes);
}

}  // namespace scatterlab
