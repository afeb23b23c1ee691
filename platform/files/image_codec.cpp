// JPEG, PNG and BMP bytes to and from images (image_codec.hpp).
//
// libjpeg and libpng report errors by longjmp. Every function that calls setjmp below holds only plain
// data (no object with a destructor is alive across a call that may jump), reads nothing it changed after
// setjmp, and turns the jump into a false return; the C++ around it (cv::Mat, strings, exceptions) lives
// outside. Each decoder works in two such steps: the header (size and layout), then, once the caller has
// checked the size and allocated the image, the pixels, written straight into the image's rows.
#include "toposlam/io/image_codec.hpp"

#include <algorithm>
#include <cctype>
#include <csetjmp>
#include <cstdio>
#include <cstring>
#include <limits>
#include <memory>

// jpeglib.h needs size_t and FILE declared first.
#include <jpeglib.h>
#include <jerror.h>
#include <png.h>
#include <zlib.h>

#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

#include "byte_order.hpp"

namespace toposlam {

namespace {

using bytes::be16;
using bytes::be32;
using bytes::le16;
using bytes::le32;

void checkPixels(std::int64_t width, std::int64_t height, std::int64_t max_pixels) {
  if (width <= 0 || height <= 0)
    throw ImageCodecError("the header says " + std::to_string(width) + "x" + std::to_string(height) + " pixels");
  if (width > max_pixels || height > max_pixels || width * height > max_pixels)
    throw ImageCodecError(std::to_string(width) + "x" + std::to_string(height) + " pixels is over the cap of " +
                          std::to_string(max_pixels) + " pixels");
  if (width > std::numeric_limits<int>::max() / 4 || height > std::numeric_limits<int>::max())
    throw ImageCodecError(std::to_string(width) + "x" + std::to_string(height) + " pixels is too large");
}

/// Grey from BGR the way OpenCV's own BMP and PNM decoders make it (0.299 R + 0.587 G + 0.114 B in 14-bit
/// fixed point, rounded), which differs by one level here and there from cv::cvtColor's.
cv::Mat greyFromBgr(const cv::Mat& bgr) {
  constexpr int kShift = 14, kR = 4899, kG = 9617, kB = (1 << kShift) - kR - kG;
  cv::Mat grey(bgr.size(), CV_8UC1);
  for (int y = 0; y < bgr.rows; ++y) {
    const auto* in = bgr.ptr<cv::Vec3b>(y);
    auto* out = grey.ptr<unsigned char>(y);
    for (int x = 0; x < bgr.cols; ++x)
      out[x] = static_cast<unsigned char>((in[x][0] * kB + in[x][1] * kG + in[x][2] * kR + (1 << (kShift - 1))) >> kShift);
  }
  return grey;
}

// ---------------------------------------------------------------------------------------------- JPEG

struct JpegError {
  jpeg_error_mgr manager;  // first: libjpeg's callbacks get a pointer to it
  std::jmp_buf jump;
  char message[JMSG_LENGTH_MAX];
  bool corrupt = false;  ///< a warning that the pixels are made up (decodeJpeg refuses the image)
};

[[noreturn]] void jpegErrorExit(j_common_ptr info) {
  auto* error = reinterpret_cast<JpegError*>(info->err);
  info->err->format_message(info, error->message);
  std::longjmp(error->jump, 1);
}

void jpegQuiet(j_common_ptr) {}  // nothing printed

// Warnings ("Corrupt JPEG data: bad Huffman code", "premature end of data segment", "Premature end of
// JPEG file") are not printed but kept: libjpeg decodes such an image with made-up pixels, so decodeJpeg
// refuses it (issue 41). One warning is harmless and common in cameras' MJPEG: bytes of padding between
// the scan and the next marker ("N extraneous bytes before marker"); the pixels are all there.
void jpegWarning(j_common_ptr info, int level) {
  if (level >= 0) return;  // trace messages
  auto* error = reinterpret_cast<JpegError*>(info->err);
  ++info->err->num_warnings;
  if (info->err->msg_code == JWRN_EXTRANEOUS_DATA || error->corrupt) return;
  error->corrupt = true;
  info->err->format_message(info, error->message);
}

/// Everything a decompression needs, created once, destroyed by the destructor (outside any setjmp).
struct JpegDecoder {
  jpeg_decompress_struct info{};
  JpegError error{};
  bool created = false;
  ~JpegDecoder() {
    if (created) jpeg_destroy_decompress(&info);
  }
};

bool jpegReadHeader(JpegDecoder& d, const unsigned char* data, std::size_t size) {
  d.info.err = jpeg_std_error(&d.error.manager);
  d.error.manager.error_exit = jpegErrorExit;
  d.error.manager.output_message = jpegQuiet;
  d.error.manager.emit_message = jpegWarning;
  if (setjmp(d.error.jump)) return false;
  jpeg_create_decompress(&d.info);
  d.created = true;
  jpeg_mem_src(&d.info, data, static_cast<unsigned long>(size));
  jpeg_save_markers(&d.info, JPEG_APP0 + 1, 0xFFFF);  // EXIF, for the orientation
  jpeg_read_header(&d.info, TRUE);
  return true;
}

/// `rows[i]` receives row i; out_color_space is set by the caller.
bool jpegReadPixels(JpegDecoder& d, unsigned char* first_row, std::size_t step) {
  if (setjmp(d.error.jump)) return false;
  jpeg_start_decompress(&d.info);
  while (d.info.output_scanline < d.info.output_height) {
    JSAMPROW row = first_row + step * d.info.output_scanline;
    jpeg_read_scanlines(&d.info, &row, 1);
  }
  jpeg_finish_decompress(&d.info);
  return true;
}

/// EXIF orientation (1..8) from a JPEG's APP1 segment; 1 (as stored) when absent or unreadable.
int exifOrientation(const jpeg_decompress_struct& info) {
  for (jpeg_saved_marker_ptr m = info.marker_list; m; m = m->next) {
    if (m->marker != JPEG_APP0 + 1 || m->data_length < 14 || std::memcmp(m->data, "Exif\0\0", 6) != 0) continue;
    const unsigned char* tiff = m->data + 6;
    const std::size_t n = m->data_length - 6;
    const bool little = tiff[0] == 'I' && tiff[1] == 'I';
    if (!little && !(tiff[0] == 'M' && tiff[1] == 'M')) return 1;
    const auto u16 = [&](std::size_t at) { return little ? le16(tiff + at) : be16(tiff + at); };
    const auto u32 = [&](std::size_t at) { return little ? le32(tiff + at) : be32(tiff + at); };
    const std::size_t ifd = u32(4);
    if (ifd + 2 > n) return 1;
    const std::size_t entries = u16(ifd);
    for (std::size_t e = 0; e < entries; ++e) {
      const std::size_t at = ifd + 2 + 12 * e;
      if (at + 12 > n) return 1;
      if (u16(at) == 0x0112) {  // Orientation, SHORT
        const std::uint32_t value = u16(at + 8);
        return value >= 1 && value <= 8 ? static_cast<int>(value) : 1;
      }
    }
    return 1;
  }
  return 1;
}

/// Turns an image stored with EXIF orientation `o` upright, as image viewers and cv::imdecode do: 5..8
/// have their sides swapped (transposed), then each is mirrored left-right (flip code 1), turned half
/// (-1) or mirrored top-bottom (0).
void applyOrientation(cv::Mat& image, int o) {
  if (o <= 1 || o > 8) return;
  if (o >= 5) cv::transpose(image, image);
  constexpr int kFlip[9] = {0, 0, 1, -1, 0, 2, 1, -1, 0};  // 2: none (5, transposed only)
  if (o != 5) cv::flip(image, image, kFlip[o]);
}

cv::Mat decodeJpeg(const unsigned char* data, std::size_t size, ImageColor color, std::int64_t max_pixels) {
  JpegDecoder d;
  if (!jpegReadHeader(d, data, size)) throw ImageCodecError(d.error.message);
  checkPixels(d.info.image_width, d.info.image_height, max_pixels);
  const int components = d.info.num_components;
  if (components != 1 && components != 3)
    throw ImageCodecError("JPEG with " + std::to_string(components) + " components (CMYK?) is not supported");
  const bool bgr = color == ImageColor::Bgr || (color == ImageColor::AsStored && components == 3);
  d.info.out_color_space = bgr ? JCS_EXT_BGR : JCS_GRAYSCALE;
  const int orientation = exifOrientation(d.info);  // before the pixels: finishing frees the saved markers
  cv::Mat image(static_cast<int>(d.info.image_height), static_cast<int>(d.info.image_width), bgr ? CV_8UC3 : CV_8UC1);
  if (!jpegReadPixels(d, image.data, image.step)) throw ImageCodecError(d.error.message);
  if (d.error.corrupt) throw ImageCodecError(std::string("corrupt JPEG data (") + d.error.message + ")");
  applyOrientation(image, orientation);
  return image;
}

// ----------------------------------------------------------------------------------------------- PNG

struct PngInput {
  const unsigned char* data;
  std::size_t size;
  std::size_t at;
};

struct PngError {
  char message[200];
};

[[noreturn]] void pngError(png_structp png, png_const_charp message) {
  auto* error = static_cast<PngError*>(png_get_error_ptr(png));
  std::snprintf(error->message, sizeof(error->message), "%s", message);
  png_longjmp(png, 1);
}

void pngQuiet(png_structp, png_const_charp) {}

void pngRead(png_structp png, png_bytep out, png_size_t length) {
  auto* in = static_cast<PngInput*>(png_get_io_ptr(png));
  if (length > in->size - in->at) png_error(png, "file ends inside the image data");
  std::memcpy(out, in->data + in->at, length);
  in->at += length;
}

struct PngDecoder {
  png_structp png = nullptr;
  png_infop info = nullptr;
  PngInput input{};
  PngError error{};
  ~PngDecoder() {
    if (png) png_destroy_read_struct(&png, info ? &info : nullptr, nullptr);
  }
};

struct PngLayout {
  png_uint_32 width = 0, height = 0;
  int bit_depth = 0, color_type = 0;
};

bool pngReadHeader(PngDecoder& d, PngLayout& layout) {
  if (setjmp(png_jmpbuf(d.png))) return false;
  png_set_read_fn(d.png, &d.input, pngRead);
  png_read_info(d.png, d.info);
  png_get_IHDR(d.png, d.info, &layout.width, &layout.height, &layout.bit_depth, &layout.color_type, nullptr, nullptr,
               nullptr);
  return true;
}

/// Sets the transforms that give 8-bit grey or BGR (as cv::imdecode asks libpng) and reads the rows.
bool pngReadPixels(PngDecoder& d, const PngLayout& layout, bool bgr, png_bytep* rows, std::size_t row_bytes) {
  if (setjmp(png_jmpbuf(d.png))) return false;
  if (layout.bit_depth == 16) png_set_strip_16(d.png);
  png_set_strip_alpha(d.png);
  if (layout.color_type == PNG_COLOR_TYPE_PALETTE) png_set_palette_to_rgb(d.png);
  if ((layout.color_type & PNG_COLOR_MASK_COLOR) == 0 && layout.bit_depth < 8) png_set_expand_gray_1_2_4_to_8(d.png);
  if ((layout.color_type & PNG_COLOR_MASK_COLOR) && bgr)
    png_set_bgr(d.png);
  else if (bgr)
    png_set_gray_to_rgb(d.png);
  else
    png_set_rgb_to_gray_fixed(d.png, 1, 29900, 58700);  // 0.299 R + 0.587 G + 0.114 B
  png_set_interlace_handling(d.png);
  png_read_update_info(d.png, d.info);
  if (png_get_rowbytes(d.png, d.info) != row_bytes) png_error(d.png, "unexpected row layout after conversion");
  png_read_image(d.png, rows);
  png_read_end(d.png, nullptr);
  return true;
}

cv::Mat decodePng(const unsigned char* data, std::size_t size, ImageColor color, std::int64_t max_pixels) {
  PngDecoder d;
  d.input = {data, size, 0};
  d.png = png_create_read_struct(PNG_LIBPNG_VER_STRING, &d.error, pngError, pngQuiet);
  if (!d.png) throw ImageCodecError("out of memory");
  d.info = png_create_info_struct(d.png);
  if (!d.info) throw ImageCodecError("out of memory");
  PngLayout layout;
  if (!pngReadHeader(d, layout)) throw ImageCodecError(d.error.message);
  checkPixels(layout.width, layout.height, max_pixels);
  // As stored: colour (palette included) or any alpha makes BGR; plain grey (even with a tRNS) stays grey.
  const bool stored_colour = (layout.color_type & (PNG_COLOR_MASK_COLOR | PNG_COLOR_MASK_ALPHA)) != 0;
  const bool bgr = color == ImageColor::Bgr || (color == ImageColor::AsStored && stored_colour);
  cv::Mat image(static_cast<int>(layout.height), static_cast<int>(layout.width), bgr ? CV_8UC3 : CV_8UC1);
  std::vector<png_bytep> rows(static_cast<std::size_t>(image.rows));
  for (int y = 0; y < image.rows; ++y) rows[static_cast<std::size_t>(y)] = image.ptr(y);
  if (!pngReadPixels(d, layout, bgr, rows.data(), static_cast<std::size_t>(image.cols) * image.elemSize()))
    throw ImageCodecError(d.error.message);
  return image;
}

// ----------------------------------------------------------------------------------------------- BMP

cv::Mat decodeBmp(const unsigned char* data, std::size_t size, ImageColor color, std::int64_t max_pixels) {
  if (size < 26) throw ImageCodecError("BMP header is cut short");
  const std::uint32_t pixels_at = le32(data + 10);
  const std::uint32_t header = le32(data + 14);
  const bool core = header == 12;  // the old OS/2 header: 16-bit sides, 3-byte palette entries
  if (!core && (header < 40 || 14 + std::size_t{header} > size)) throw ImageCodecError("BMP header is not one we read");
  const std::int64_t width = core ? le16(data + 18) : static_cast<std::int32_t>(le32(data + 18));
  const std::int64_t signed_height = core ? le16(data + 20) : static_cast<std::int32_t>(le32(data + 22));
  const int bpp = static_cast<int>(le16(data + (core ? 24 : 28)));
  const std::uint32_t compression = core ? 0 : le32(data + 30);
  const bool top_down = signed_height < 0;
  const std::int64_t height = top_down ? -signed_height : signed_height;
  checkPixels(width, height, max_pixels);
  if (compression == 1 || compression == 2)
    throw ImageCodecError("BMP with RLE compression is not supported (save it as PNG or uncompressed BMP)");
  const bool bitfields = compression == 3;
  if (compression != 0 && !bitfields) throw ImageCodecError("BMP compression " + std::to_string(compression) + " is not supported");
  if (bpp != 1 && bpp != 4 && bpp != 8 && bpp != 16 && bpp != 24 && bpp != 32)
    throw ImageCodecError("BMP with " + std::to_string(bpp) + " bits per pixel is not supported");
  if (bitfields && bpp != 16 && bpp != 32) throw ImageCodecError("BMP bit fields with " + std::to_string(bpp) + " bits per pixel");
  // 16 bits: 5-5-5 unless the bit fields say 5-6-5 (the green mask, after a 40-byte header or inside a longer one).
  const bool rgb565 = bitfields && bpp == 16 && 14 + 40 + 12 <= size && le32(data + 14 + 40 + 4) == 0x07E0;

  std::vector<cv::Vec3b> palette;
  if (bpp <= 8) {
    const std::size_t entry = core ? 3 : 4;
    std::size_t count = core ? 0 : le32(data + 46);
    if (count == 0 || count > (std::size_t{1} << bpp)) count = std::size_t{1} << bpp;
    const std::size_t from = 14 + header;
    if (from + count * entry > size) throw ImageCodecError("BMP palette is cut short");
    for (std::size_t i = 0; i < count; ++i)
      palette.emplace_back(data[from + i * entry], data[from + i * entry + 1], data[from + i * entry + 2]);
    palette.resize(std::size_t{1} << bpp, cv::Vec3b(0, 0, 0));
  }
  const std::size_t stride = ((static_cast<std::size_t>(width) * static_cast<std::size_t>(bpp) + 31) / 32) * 4;
  if (pixels_at > size || stride * static_cast<std::size_t>(height) > size - pixels_at)
    throw ImageCodecError("BMP pixel data is cut short");

  const bool grey_palette = !palette.empty() && std::all_of(palette.begin(), palette.end(), [](const cv::Vec3b& c) {
    return c[0] == c[1] && c[1] == c[2];
  });
  cv::Mat bgr(static_cast<int>(height), static_cast<int>(width), CV_8UC3);
  for (int y = 0; y < bgr.rows; ++y) {
    const unsigned char* row = data + pixels_at + stride * static_cast<std::size_t>(top_down ? y : bgr.rows - 1 - y);
    auto* out = bgr.ptr<cv::Vec3b>(y);
    for (int x = 0; x < bgr.cols; ++x) {
      switch (bpp) {
        case 1: out[x] = palette[(row[x / 8] >> (7 - x % 8)) & 1]; break;
        case 4: out[x] = palette[(row[x / 2] >> (x % 2 ? 0 : 4)) & 15]; break;
        case 8: out[x] = palette[row[x]]; break;
        case 16: {
          const std::uint32_t v = le16(row + 2 * x);
          const std::uint32_t r = rgb565 ? (v >> 11) & 31 : (v >> 10) & 31;
          const std::uint32_t g = rgb565 ? ((v >> 5) & 63) << 2 : ((v >> 5) & 31) << 3;
          const std::uint32_t b = v & 31;
          out[x] = cv::Vec3b(static_cast<unsigned char>(b << 3), static_cast<unsigned char>(g), static_cast<unsigned char>(r << 3));
          break;
        }
        case 24: out[x] = cv::Vec3b(row[3 * x], row[3 * x + 1], row[3 * x + 2]); break;
        default: out[x] = cv::Vec3b(row[4 * x], row[4 * x + 1], row[4 * x + 2]); break;  // 32: B,G,R,X
      }
    }
  }
  if (color == ImageColor::Bgr || (color == ImageColor::AsStored && !grey_palette)) return bgr;
  return greyFromBgr(bgr);
}

// ----------------------------------------------------------------------------------------------- PNM

/// Reads the next whole number of a PNM header or ASCII body, skipping whitespace and # comments.
bool pnmNumber(const unsigned char* data, std::size_t size, std::size_t& at, std::uint32_t& value) {
  for (;;) {
    while (at < size && std::isspace(data[at])) ++at;
    if (at < size && data[at] == '#') {
      while (at < size && data[at] != '\n' && data[at] != '\r') ++at;
      continue;
    }
    break;
  }
  if (at >= size || !std::isdigit(data[at])) return false;
  std::uint64_t v = 0;
  while (at < size && std::isdigit(data[at])) {
    v = v * 10 + static_cast<std::uint64_t>(data[at++] - '0');
    if (v > 0xFFFFFFFFu) return false;
  }
  value = static_cast<std::uint32_t>(v);
  return true;
}

/// P1..P6 (ASCII and binary bitmaps, grey maps, colour maps). A sample above the maximum is taken as the
/// maximum; 8-bit samples are kept as they are, 16-bit ones (maximum above 255) keep their high byte;
/// in bitmaps 1 is black.
cv::Mat decodePnm(const unsigned char* data, std::size_t size, ImageColor color, std::int64_t max_pixels) {
  const int kind = data[1] - '0';
  const bool bitmap = kind == 1 || kind == 4, binary = kind >= 4, colour = kind == 3 || kind == 6;
  std::size_t at = 2;
  std::uint32_t width = 0, height = 0, max_value = 1;
  if (!pnmNumber(data, size, at, width) || !pnmNumber(data, size, at, height) ||
      (!bitmap && !pnmNumber(data, size, at, max_value)))
    throw ImageCodecError("PNM header is cut short or not numbers");
  checkPixels(width, height, max_pixels);
  if (max_value == 0 || max_value > 65535) throw ImageCodecError("PNM maximum value " + std::to_string(max_value) + " is not in 1..65535");
  if (binary) ++at;  // the single whitespace before the samples
  const int channels = colour ? 3 : 1;
  cv::Mat image(static_cast<int>(height), static_cast<int>(width), colour ? CV_8UC3 : CV_8UC1);
  const std::size_t samples_per_row = static_cast<std::size_t>(width) * static_cast<std::size_t>(channels);
  const std::size_t bytes_per_sample = max_value > 255 ? 2 : 1;
  const std::size_t row_bytes = bitmap ? (width + 7) / 8 : samples_per_row * bytes_per_sample;
  if (binary && (at > size || row_bytes * height > size - at)) throw ImageCodecError("PNM pixel data is cut short");
  for (int y = 0; y < image.rows; ++y) {
    unsigned char* out = image.ptr(y);
    for (std::size_t i = 0; i < samples_per_row; ++i) {
      std::uint32_t v = 0;
      if (!binary) {
        if (!pnmNumber(data, size, at, v)) throw ImageCodecError("PNM pixel data is cut short or not numbers");
      } else if (bitmap) {
        v = (data[at + i / 8] >> (7 - i % 8)) & 1;
      } else if (bytes_per_sample == 2) {
        v = be16(data + at + 2 * i);
      } else {
        v = data[at + i];
      }
      if (bitmap) {
        out[i] = v ? 0 : 255;
        continue;
      }
      v = std::min(v, max_value);
      out[i] = static_cast<unsigned char>(max_value > 255 ? v >> 8 : v);
    }
    if (binary) at += row_bytes;
    for (std::size_t x = 0; colour && x < width; ++x) std::swap(out[3 * x], out[3 * x + 2]);  // R,G,B to B,G,R
  }
  if (colour == (color != ImageColor::Grey) || (color == ImageColor::AsStored)) return image;
  if (colour) return greyFromBgr(image);
  cv::Mat converted;
  cv::cvtColor(image, converted, cv::COLOR_GRAY2BGR);
  return converted;
}

// -------------------------------------------------------------------------------------------- encoding

struct JpegOutput {
  jpeg_destination_mgr manager;  // first: libjpeg gets a pointer to it
  std::vector<unsigned char>* out;
};

constexpr std::size_t kJpegChunk = 16384;

void jpegInitDestination(j_compress_ptr info) {
  auto* dest = reinterpret_cast<JpegOutput*>(info->dest);
  dest->out->resize(kJpegChunk);
  dest->manager.next_output_byte = dest->out->data();
  dest->manager.free_in_buffer = dest->out->size();
}

boolean jpegEmptyOutput(j_compress_ptr info) {
  auto* dest = reinterpret_cast<JpegOutput*>(info->dest);
  const std::size_t used = dest->out->size();
  bool grown = true;
  try {  // no exception may cross libjpeg's C frames: out of memory becomes libjpeg's own error
    dest->out->resize(used + kJpegChunk);
  } catch (const std::bad_alloc&) {
    grown = false;
  }
  if (!grown) {
    info->err->msg_code = JERR_OUT_OF_MEMORY;
    info->err->error_exit(reinterpret_cast<j_common_ptr>(info));
  }
  dest->manager.next_output_byte = dest->out->data() + used;
  dest->manager.free_in_buffer = kJpegChunk;
  return TRUE;
}

void jpegTermDestination(j_compress_ptr info) {
  auto* dest = reinterpret_cast<JpegOutput*>(info->dest);
  dest->out->resize(dest->out->size() - dest->manager.free_in_buffer);
}

struct JpegEncoder {
  jpeg_compress_struct info{};
  JpegError error{};
  JpegOutput output{};
  bool created = false;
  ~JpegEncoder() {
    if (created) jpeg_destroy_compress(&info);
  }
};

bool jpegCompress(JpegEncoder& e, const cv::Mat& image, int quality) {
  e.info.err = jpeg_std_error(&e.error.manager);
  e.error.manager.error_exit = jpegErrorExit;
  e.error.manager.output_message = jpegQuiet;
  if (setjmp(e.error.jump)) return false;
  jpeg_create_compress(&e.info);
  e.created = true;
  e.info.dest = &e.output.manager;
  e.output.manager.init_destination = jpegInitDestination;
  e.output.manager.empty_output_buffer = jpegEmptyOutput;
  e.output.manager.term_destination = jpegTermDestination;
  e.info.image_width = static_cast<JDIMENSION>(image.cols);
  e.info.image_height = static_cast<JDIMENSION>(image.rows);
  const int channels = image.channels();
  e.info.input_components = channels;
  e.info.in_color_space = channels == 1 ? JCS_GRAYSCALE : channels == 3 ? JCS_EXT_BGR : JCS_EXT_BGRX;
  jpeg_set_defaults(&e.info);
  jpeg_set_quality(&e.info, quality, TRUE);  // baseline quantisation tables, as cv::imencode
  jpeg_start_compress(&e.info, TRUE);
  while (e.info.next_scanline < e.info.image_height) {
    JSAMPROW row = const_cast<JSAMPROW>(image.ptr(static_cast<int>(e.info.next_scanline)));
    jpeg_write_scanlines(&e.info, &row, 1);
  }
  jpeg_finish_compress(&e.info);
  return true;
}

void pngWrite(png_structp png, png_bytep data, png_size_t length) {
  auto* out = static_cast<std::vector<unsigned char>*>(png_get_io_ptr(png));
  bool grown = true;
  try {  // no exception may cross libpng's C frames
    out->insert(out->end(), data, data + length);
  } catch (const std::bad_alloc&) {
    grown = false;
  }
  if (!grown) png_error(png, "out of memory");
}

void pngFlush(png_structp) {}

struct PngEncoder {
  png_structp png = nullptr;
  png_infop info = nullptr;
  PngError error{};
  ~PngEncoder() {
    if (png) png_destroy_write_struct(&png, info ? &info : nullptr);
  }
};

bool pngCompress(PngEncoder& e, const cv::Mat& image, std::vector<unsigned char>& out, png_bytep* rows) {
  if (setjmp(png_jmpbuf(e.png))) return false;
  png_set_write_fn(e.png, &out, pngWrite, pngFlush);
  // cv::imencode's defaults: fast, and small enough for drawings and thumbnails.
  png_set_filter(e.png, PNG_FILTER_TYPE_BASE, PNG_FILTER_SUB);
  png_set_compression_level(e.png, Z_BEST_SPEED);
  png_set_compression_strategy(e.png, Z_RLE);
  const int channels = image.channels();
  png_set_IHDR(e.png, e.info, static_cast<png_uint_32>(image.cols), static_cast<png_uint_32>(image.rows), 8,
               channels == 1 ? PNG_COLOR_TYPE_GRAY : channels == 3 ? PNG_COLOR_TYPE_RGB : PNG_COLOR_TYPE_RGB_ALPHA,
               PNG_INTERLACE_NONE, PNG_COMPRESSION_TYPE_DEFAULT, PNG_FILTER_TYPE_DEFAULT);
  png_write_info(e.png, e.info);
  png_set_bgr(e.png);
  png_write_image(e.png, rows);
  png_write_end(e.png, e.info);
  return true;
}

void encodeBmp(const cv::Mat& image, std::vector<unsigned char>& out) {
  const bool grey = image.channels() == 1;
  const int bpp = grey ? 8 : 24;
  const std::size_t stride = ((static_cast<std::size_t>(image.cols) * bpp / 8) + 3) / 4 * 4;
  const std::size_t palette = grey ? 256 * 4 : 0;
  const std::size_t pixels_at = 14 + 40 + palette;
  const std::size_t total = pixels_at + stride * static_cast<std::size_t>(image.rows);
  out.assign(total, 0);
  const auto put16 = [&](std::size_t at, std::uint32_t v) {
    out[at] = static_cast<unsigned char>(v);
    out[at + 1] = static_cast<unsigned char>(v >> 8);
  };
  const auto put32 = [&](std::size_t at, std::uint32_t v) {
    put16(at, v & 0xFFFF);
    put16(at + 2, v >> 16);
  };
  out[0] = 'B';
  out[1] = 'M';
  put32(2, static_cast<std::uint32_t>(total));
  put32(10, static_cast<std::uint32_t>(pixels_at));
  put32(14, 40);
  put32(18, static_cast<std::uint32_t>(image.cols));
  put32(22, static_cast<std::uint32_t>(image.rows));
  put16(26, 1);
  put16(28, static_cast<std::uint32_t>(bpp));
  if (grey) {
    for (std::uint32_t i = 0; i < 256; ++i) put32(54 + 4 * i, i * 0x010101u);
  }
  for (int y = 0; y < image.rows; ++y) {  // bottom-up
    unsigned char* row = out.data() + pixels_at + stride * static_cast<std::size_t>(image.rows - 1 - y);
    const unsigned char* in = image.ptr(y);
    const int channels = image.channels();
    for (int x = 0; x < image.cols; ++x) {
      if (grey) {
        row[x] = in[x];
      } else {
        std::memcpy(row + 3 * x, in + channels * x, 3);
      }
    }
  }
}

}  // namespace

cv::Mat decodeImage(const unsigned char* data, std::size_t size, ImageColor color, std::int64_t max_pixels) {
  if (size >= 3 && data[0] == 0xFF && data[1] == 0xD8 && data[2] == 0xFF) return decodeJpeg(data, size, color, max_pixels);
  if (size >= 8 && std::memcmp(data, "\x89PNG\r\n\x1a\n", 8) == 0) return decodePng(data, size, color, max_pixels);
  if (size >= 2 && data[0] == 'B' && data[1] == 'M') return decodeBmp(data, size, color, max_pixels);
  if (size >= 3 && data[0] == 'P' && data[1] >= '1' && data[1] <= '6' && std::isspace(data[2]))
    return decodePnm(data, size, color, max_pixels);
  throw ImageCodecError("not a JPEG, PNG, BMP or PNM image");
}

std::optional<ImageFormat> imageFormatOfPath(const std::string& path) {
  const std::size_t dot = path.find_last_of('.');
  if (dot == std::string::npos || path.find('/', dot) != std::string::npos) return std::nullopt;
  std::string extension = path.substr(dot + 1);
  for (char& c : extension) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  if (extension == "jpg" || extension == "jpeg") return ImageFormat::Jpeg;
  if (extension == "png") return ImageFormat::Png;
  if (extension == "bmp") return ImageFormat::Bmp;
  return std::nullopt;
}

void encodeImage(const cv::Mat& image, ImageFormat format, std::vector<unsigned char>& out, int jpeg_quality) {
  if (image.empty()) throw ImageCodecError("cannot encode an empty image");
  if (image.depth() != CV_8U || (image.channels() != 1 && image.channels() != 3 && image.channels() != 4))
    throw ImageCodecError("cannot encode an image of type " + cv::typeToString(image.type()) +
                          " (8-bit grey, BGR or BGRA only)");
  out.clear();
  switch (format) {
    case ImageFormat::Jpeg: {
      JpegEncoder e;
      e.output.out = &out;
      if (!jpegCompress(e, image, std::clamp(jpeg_quality, 0, 100))) throw ImageCodecError(e.error.message);
      return;
    }
    case ImageFormat::Png: {
      PngEncoder e;
      e.png = png_create_write_struct(PNG_LIBPNG_VER_STRING, &e.error, pngError, pngQuiet);
      if (!e.png) throw ImageCodecError("out of memory");
      e.info = png_create_info_struct(e.png);
      if (!e.info) throw ImageCodecError("out of memory");
      std::vector<png_bytep> rows(static_cast<std::size_t>(image.rows));
      for (int y = 0; y < image.rows; ++y) rows[static_cast<std::size_t>(y)] = const_cast<png_bytep>(image.ptr(y));
      if (!pngCompress(e, image, out, rows.data())) throw ImageCodecError(e.error.message);
      return;
    }
    case ImageFormat::Bmp:
      encodeBmp(image, out);
      return;
  }
}

std::vector<unsigned char> encodeImage(const cv::Mat& image, ImageFormat format, int jpeg_quality) {
  std::vector<unsigned char> out;
  encodeImage(image, format, out, jpeg_quality);
  return out;
}

}  // namespace toposlam
