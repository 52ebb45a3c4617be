// Builds small PLY files in memory for the loader tests (any layout, format and values).
#pragma once

#include <cstdint>
#include <cstring>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

namespace flashgs::test {

struct PlyBuilder {
  std::string format = "binary_little_endian";
  std::vector<std::pair<std::string, std::string>> properties;  // (type, name)
  std::vector<std::vector<double>> vertices;
  long long declared_count = -1;  // -1: the real count
  // Other elements: header lines and data bytes, before and after the vertex element.
  std::string leading_elements, leading_data, trailing_elements, trailing_data;
  std::vector<std::string> comments;  // header comment lines (after the builder's own)

  // The INRIA layout with SH degree `degree` and `n` plausible Gaussians.
  static PlyBuilder inria(int degree, int n) {
    PlyBuilder b;
    for (const char* p : {"x", "y", "z", "nx", "ny", "nz", "f_dc_0", "f_dc_1", "f_dc_2"}) b.properties.push_back({"float", p});
    const int rest = ((degree + 1) * (degree + 1) - 1) * 3;
    for (int k = 0; k < rest; ++k) b.properties.push_back({"float", "f_rest_" + std::to_string(k)});
    for (const char* p : {"opacity", "scale_0", "scale_1", "scale_2", "rot_0", "rot_1", "rot_2", "rot_3"})
      b.properties.push_back({"float", p});
    for (int i = 0; i < n; ++i) {
      std::vector<double> v;
      for (const auto& [type, name] : b.properties) {
        if (name == "x") v.push_back(0.1 * i);
        else if (name == "z") v.push_back(2.0 + 0.01 * i);
        else if (name.rfind("scale_", 0) == 0) v.push_back(-3.0);
        else if (name == "rot_0") v.push_back(1.0);
        else if (name == "opacity") v.push_back(1.0);
        else if (name.rfind("f_", 0) == 0) v.push_back(0.01 * (i + 1));
        else v.push_back(0.0);
      }
      b.vertices.push_back(v);
    }
    return b;
  }

  int index_of(const std::string& name) const {
    for (std::size_t i = 0; i < properties.size(); ++i)
      if (properties[i].second == name) return static_cast<int>(i);
    return -1;
  }

  std::string header() const {
    std::ostringstream h;
    h << "ply\nformat " << format << " 1.0\ncomment built by the flashgs tests\n";
    for (const std::string& c : comments) h << "comment " << c << "\n";
    h << leading_elements;
    h << "element vertex " << (declared_count >= 0 ? declared_count : static_cast<long long>(vertices.size())) << "\n";
    for (const auto& [type, name] : properties) h << "property " << type << " " << name << "\n";
    h << trailing_elements << "end_header\n";
    return h.str();
  }

  std::string bytes() const {
    std::string out = header() + leading_data;
    const bool big = format == "binary_big_endian";
    for (const auto& v : vertices) {
      if (format == "ascii") {
        for (std::size_t i = 0; i < v.size(); ++i) out += (i ? " " : "") + number(v[i]);
        out += "\n";
        continue;
      }
      for (std::size_t i = 0; i < v.size(); ++i) {
        const std::string& type = properties[i].first;
        unsigned char raw[8];
        int n = 4;
        if (type == "float") { const float f = static_cast<float>(v[i]); std::memcpy(raw, &f, 4); }
        else if (type == "double") { std::memcpy(raw, &v[i], 8); n = 8; }
        else if (type == "uchar") { raw[0] = static_cast<unsigned char>(v[i]); n = 1; }
        else { const std::int32_t k = static_cast<std::int32_t>(v[i]); std::memcpy(raw, &k, 4); }
        for (int b = 0; b < n; ++b) out += static_cast<char>(big ? raw[n - 1 - b] : raw[b]);
      }
    }
    return out + trailing_data;
  }

 private:
  static std::string number(double v) {
    std::ostringstream s;
    s.precision(17);
    s << v;
    return s.str();
  }
};

}  // namespace flashgs::test
