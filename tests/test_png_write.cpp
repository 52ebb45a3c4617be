// PNG output goes through libpng, without loading OpenImageIO's module (whose libraries cost a
// program 0.3-0.45 s): the bytes written are the image's clamped and rounded values.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <string>

#include "flashgs/error.h"
#include "flashgs/image_io.h"
#include "flashgs/netpbm.h"

namespace flashgs {
namespace {

bool oiio_is_mapped() {
  std::ifstream maps("/proc/self/maps");
  std::string line;
  while (std::getline(maps, line))
    if (line.find("libOpenImageIO") != std::string::npos) return true;
  return false;
}

TEST(PngWrite, WritesTheImagesBytesWithoutOpenImageIo) {
  if (!image_io_writes_png()) GTEST_SKIP() << "built without libpng and OpenImageIO: no PNG";
  Image image;
  image.resize(37, 11);  // odd sizes: rows are not padded to a multiple of anything
  for (int y = 0; y < image.height; ++y)
    for (int x = 0; x < image.width; ++x)
      for (int c = 0; c < 3; ++c) image.rgb[(static_cast<std::size_t>(y) * image.width + x) * 3 + c] = -0.2f + 0.04f * x + 0.1f * y + 0.3f * c;
  const std::string path = std::string(FLASHGS_TEST_OUTPUT_DIR) + "/png_write.png";
  std::filesystem::remove(path);
  ASSERT_TRUE(image_format_writable(path));
  write_image(image, path);
  EXPECT_FALSE(oiio_is_mapped()) << "writing a PNG loaded OpenImageIO";
  std::ifstream file(path, std::ios::binary);
  char signature[8] = {};
  file.read(signature, 8);
  EXPECT_EQ(std::string(signature, 8), std::string("\x89PNG\r\n\x1a\n", 8));
  if (!image_io_has_oiio()) GTEST_SKIP() << "no OpenImageIO to read the PNG back";
  const Image back = read_image(path);
  ASSERT_EQ(back.width, image.width);
  ASSERT_EQ(back.height, image.height);
  for (std::size_t i = 0; i < image.rgb.size(); ++i)
    ASSERT_EQ(static_cast<int>(back.rgb[i] * 255.0f + 0.5f), static_cast<int>(to_byte(image.rgb[i]))) << "value " << i;
}

TEST(PngWrite, AFolderThatIsNotThereIsOneLineNamingThePath) {
  if (!image_io_writes_png()) GTEST_SKIP() << "built without libpng and OpenImageIO: no PNG";
  const std::string path = std::string(FLASHGS_TEST_OUTPUT_DIR) + "/no_such_folder/x.png";
  try {
    Image image;
    image.resize(4, 4);
    write_image(image, path);
    FAIL() << "wrote into a folder that does not exist";
  } catch (const Error& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find(path), std::string::npos) << what;
    EXPECT_EQ(what.find('\n'), std::string::npos) << what;
  }
}

}  // namespace
}  // namespace flashgs
