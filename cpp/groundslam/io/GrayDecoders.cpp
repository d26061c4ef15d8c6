#include "groundslam/io/GrayDecoders.hpp"

#include <csetjmp>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <vector>

#include <jpeglib.h>
#include <png.h>

namespace groundslam {
namespace {

/// An open C file, closed on every way out.
struct File {
  explicit File(const std::string& path) : handle(std::fopen(path.c_str(), "rb")) {}
  ~File() {
    if (handle) std::fclose(handle);
  }
  File(const File&) = delete;
  File& operator=(const File&) = delete;
  std::FILE* handle;
};

/// True when the JPEG file has an APP1 segment starting "Exif" before its first scan.
bool hasExif(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  unsigned char head[2];
  if (!in.read(reinterpret_cast<char*>(head), 2) || head[0] != 0xFF || head[1] != 0xD8) return false;
  for (int segments = 0; segments < 1000; ++segments) {
    int byte = in.get();
    if (byte != 0xFF) return false;                              // not a marker
    while (byte == 0xFF) byte = in.get();                        // fill bytes before the marker code
    unsigned char size[2];
    if (byte == EOF || byte == 0xDA || !in.read(reinterpret_cast<char*>(size), 2)) return false;  // the scan: no EXIF before it
    const unsigned char marker[2] = {0xFF, static_cast<unsigned char>(byte)};
    const int length = (size[0] << 8) | size[1];
    if (length < 2) return false;
    if (marker[1] == 0xE1 && length >= 8) {
      char id[4];
      if (!in.read(id, 4)) return false;
      if (std::memcmp(id, "Exif", 4) == 0) return true;
      in.seekg(length - 2 - 4, std::ios::cur);
    } else {
      in.seekg(length - 2, std::ios::cur);
    }
  }
  return false;
}

// libpng and libjpeg report errors by longjmp back into the function that called setjmp: everything those
// functions allocate lives in their callers' frames (the image, the row pointers, the file), so a jump skips no
// destructor, and their own locals changed after setjmp are volatile.

bool littleEndian() {
  const std::uint16_t one = 1;
  unsigned char first = 0;
  std::memcpy(&first, &one, 1);
  return first == 1;
}

/// The most pixels OpenCV's decoders accept (CV_IO_MAX_IMAGE_PIXELS): larger files go to OpenCV, which refuses them.
constexpr double kMaxPixels = 1 << 30;

bool readPng(std::FILE* file, cv::Mat& out, std::vector<png_bytep>& rows) {
  png_structp png = png_create_read_struct(PNG_LIBPNG_VER_STRING, nullptr, nullptr, nullptr);
  if (!png) return false;
  png_infop info = png_create_info_struct(png), end = png_create_info_struct(png);
  if (!info || !end) {
    png_destroy_read_struct(&png, info ? &info : nullptr, end ? &end : nullptr);
    return false;
  }
  volatile bool ok = false;
  if (setjmp(png_jmpbuf(png)) == 0) {
    png_init_io(png, file);
    png_read_info(png, info);
    const png_uint_32 width = png_get_image_width(png, info), height = png_get_image_height(png, info);
    const int depth = png_get_bit_depth(png, info), colour = png_get_color_type(png, info);
    // OpenCV turns an image by an EXIF orientation: files with EXIF are left to it.
    const bool plain_grey = colour == PNG_COLOR_TYPE_GRAY && (depth == 8 || depth == 16) &&
                            png_get_interlace_type(png, info) == PNG_INTERLACE_NONE && !png_get_valid(png, info, PNG_INFO_tRNS) &&
                            !png_get_valid(png, info, PNG_INFO_eXIf);
    bool allocated = false;
    if (plain_grey && width > 0 && height > 0 && static_cast<double>(width) * height <= kMaxPixels) {
      try {  // a failed allocation must not leave the function past libpng's cleanup
        out.create(static_cast<int>(height), static_cast<int>(width), depth == 16 ? CV_16U : CV_8U);
        rows.resize(height);
        allocated = true;
      } catch (...) {
      }
    }
    if (allocated) {
      if (depth == 16 && littleEndian()) png_set_swap(png);  // PNG stores 16-bit samples big-endian
      for (png_uint_32 r = 0; r < height; ++r) rows[r] = out.ptr<png_byte>(static_cast<int>(r));
      png_read_image(png, rows.data());
      png_read_end(png, end);
      ok = !png_get_valid(png, end, PNG_INFO_eXIf);  // EXIF after the pixels: OpenCV's turn too
    }
  }
  png_destroy_read_struct(&png, &info, &end);
  return ok;
}

struct JpegError {
  jpeg_error_mgr manager;
  std::jmp_buf jump;
};

void jpegFail(j_common_ptr info) { std::longjmp(reinterpret_cast<JpegError*>(info->err)->jump, 1); }
void jpegQuiet(j_common_ptr, int) {}  // warnings (e.g. a truncated file libjpeg can still decode) are not printed

bool readJpeg(std::FILE* file, int reduction, cv::Mat& out) {
  jpeg_decompress_struct info;
  JpegError error;
  info.err = jpeg_std_error(&error.manager);
  error.manager.error_exit = jpegFail;
  error.manager.emit_message = jpegQuiet;
  volatile bool created = false, ok = false;
  if (setjmp(error.jump) == 0) {  // before jpeg_create_decompress, which may fail too
    jpeg_create_decompress(&info);
    created = true;
    jpeg_stdio_src(&info, file);
    jpeg_read_header(&info, TRUE);
    bool allocated = false;
    if (info.jpeg_color_space != JCS_CMYK && info.jpeg_color_space != JCS_YCCK &&
        static_cast<double>(info.image_width) * info.image_height <= kMaxPixels) {
      // What OpenCV's JPEG decoder asks libjpeg for when it reads grey, reduced by scale_denom.
      info.scale_num = 1;
      info.scale_denom = static_cast<unsigned>(reduction);
      info.out_color_space = JCS_GRAYSCALE;
      jpeg_start_decompress(&info);
      try {  // a failed allocation must not leave the function past libjpeg's cleanup
        out.create(static_cast<int>(info.output_height), static_cast<int>(info.output_width), CV_8U);
        allocated = true;
      } catch (...) {
      }
    }
    if (allocated) {
      while (info.output_scanline < info.output_height) {
        JSAMPROW row = out.ptr<JSAMPLE>(static_cast<int>(info.output_scanline));
        jpeg_read_scanlines(&info, &row, 1);
      }
      jpeg_finish_decompress(&info);
      ok = true;
    }
  }
  if (created) jpeg_destroy_decompress(&info);
  return ok;
}

}  // namespace

std::optional<cv::Mat> decodeGrayPng(const std::string& path) {
  File file(path);
  if (!file.handle) return std::nullopt;
  unsigned char signature[8];
  if (std::fread(signature, 1, 8, file.handle) != 8 || png_sig_cmp(signature, 0, 8) != 0) return std::nullopt;
  std::rewind(file.handle);
  cv::Mat image;
  std::vector<png_bytep> rows;
  if (!readPng(file.handle, image, rows)) return std::nullopt;
  return image;
}

std::optional<cv::Mat> decodeGrayJpeg(const std::string& path, int reduction) {
  if (reduction != 1 && reduction != 2 && reduction != 4 && reduction != 8) return std::nullopt;
  if (hasExif(path)) return std::nullopt;
  File file(path);
  if (!file.handle) return std::nullopt;
  cv::Mat image;
  if (!readJpeg(file.handle, reduction, image)) return std::nullopt;
  return image;
}

}  // namespace groundslam
