#include "core/image.h"

#include <ImfChannelList.h>
#include <ImfFrameBuffer.h>
#include <ImfHeader.h>
#include <ImfIO.h>
#include <ImfInputFile.h>
#include <ImfOutputFile.h>
#include <png.h>

#include <cstring>
#include <limits>

#include "core/atomic_file.h"
#include "core/error.h"

namespace scatterlab {

namespace {

/// OpenEXR output into the checked stream of writeFileAtomically (OpenEXR's own StdOFStream
/// leaves the final flush of its std::ofstream unchecked).
class ExrOStream : public Imf::OStream {
 public:
  ExrOStream(std::ostream& os, const std::string& name) : Imf::OStream(name.c_str()), os_(os) {}
  void write(const char c[], int n) override {
    if (!os_.write(c, n)) throw IoError("write failed");
  }
  uint64_t tellp() override { return uint64_t(os_.tellp()); }
  void seekp(uint64_t pos) override {
    if (!os_.seekp(std::streamoff(pos))) throw IoError("seek failed");
  }

 private:
  std::ostream& os_;
};

}  // namespace

void writeExr(const Image& img, const std::string& path) {
  if (img.width() <= 0 || img.height() <= 0) throw IoError("cannot write an empty image");
  writeFileAtomically(path, [&](std::ostream& os) {
    try {
      Imf::Header header(img.width(), img.height());
      for (const char* c : {"R", "G", "B"}) header.channels().insert(c, Imf::Channel(Imf::FLOAT));
      ExrOStream stream(os, path);
      Imf::OutputFile file(stream, header);
      Imf::FrameBuffer fb;
      char* base = const_cast<char*>(reinterpret_cast<const char*>(img.pixels().data()));
      const size_t xs = sizeof(Vec3), ys = sizeof(Vec3) * img.width();
      fb.insert("R", Imf::Slice(Imf::FLOAT, base, xs, ys));
      fb.insert("G", Imf::Slice(Imf::FLOAT, base + sizeof(float), xs, ys));
      fb.insert("B", Imf::Slice(Imf::FLOAT, base + 2 * sizeof(float), xs, ys));
      file.setFrameBuffer(fb);
      file.writePixels(img.height());
    } catch (const std::exception& e) {
      throw IoError("cannot write EXR '" + path + "': " + e.what());
    }
  });
}

Image readExr(const std::string& path) {
  checkReadableFile(path, "image");
  try {
    Imf::InputFile file(path.c_str());
    const Imath::Box2i dw = file.header().dataWindow();
    const int w = dw.max.x - dw.min.x + 1, h = dw.max.y - dw.min.y + 1;
    const Imf::ChannelList& ch = file.header().channels();
    if (!ch.findChannel("R") && !ch.findChannel("G") && !ch.findChannel("B"))
      throw IoError("no R, G or B channel");
    Image img(w, h);
    Imf::FrameBuffer fb;
    char* base = reinterpret_cast<char*>(img.pixels().data());
    const size_t xs = sizeof(Vec3), ys = sizeof(Vec3) * w;
    base -= (dw.min.x * xs + dw.min.y * ys);
    fb.insert("R", Imf::Slice(Imf::FLOAT, base, xs, ys, 1, 1, 0.0));
    fb.insert("G", Imf::Slice(Imf::FLOAT, base + sizeof(float), xs, ys, 1, 1, 0.0));
    fb.insert("B", Imf::Slice(Imf::FLOAT, base + 2 * sizeof(float), xs, ys, 1, 1, 0.0));
    file.setFrameBuffer(fb);
    file.readPixels(dw.min.y, dw.max.y);
    return img;
  } catch (const IoError& e) {
    throw IoError("cannot read EXR '" + path + "': " + e.what());
  } catch (const std::exception& e) {
    throw IoError("cannot read EXR '" + path + "': " + e.what());
  }
}

float toneMapSrgb(float linear, float exposure) {
  float v = linear * std::exp2(exposure);
  if (!(v > 0.0f)) return 0.0f;  // also maps NaN to 0
  if (v >= 1.0f) return 1.0f;
  return v <= 0.0031308f ? 12.92f * v : 1.055f * std::pow(v, 1.0f / 2.4f) - 0.055f;
}

void writePng(const Image& img, const std::string& path, float exposure) {
  if (img.width() <= 0 || img.height() <= 0) throw IoError("cannot write an empty image");
  std::vector<unsigned char> buf(size_t(img.width()) * img.height() * 3);
  for (size_t i = 0; i < img.pixels().size(); ++i)
    for (int c = 0; c < 3; ++c)
      buf[3 * i + c] =
          static_cast<unsigned char>(toneMapSrgb(img.pixels()[i][c], exposure) * 255.0f + 0.5f);
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
