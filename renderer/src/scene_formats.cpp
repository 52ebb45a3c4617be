// The registry of scene-file formats: how each is recognised, what it is called, and which
// parser reads it; load_scene_file picks the first that recognises the file.
#include "flashgs/scene_formats.h"

#include <algorithm>
#include <cctype>
#include <chrono>
#include <cstring>
#include <filesystem>
#include <new>
#include <limits>
#include <string_view>
#include <vector>

#include "flashgs/compressed_formats.h"
#include "flashgs/error.h"
#include "flashgs/file_access.h"
#include "flashgs/frame_memory.h"
#include "flashgs/io.h"
#include "format_readers.h"
#include "format_writers.h"
#include "sog_meta.h"
#include "zip_archive.h"

namespace flashgs {
namespace {

// What a recogniser sees: the file's name and its first kStartBytes (all of them for small
// files; up to kMaxSogJsonBytes for a JSON object, see read_recognition_start).
struct FileStart {
  const std::string& name;
  std::string_view bytes;
};

using Recogniser = bool (*)(const FileStart&);
// What the file's start declares, given the file's size; throws when the two disagree.
using Declarer = DeclaredScene (*)(const FileStart&, std::uint64_t file_size);
using Parser = Scene (*)(const char*, std::size_t, const std::string&, LoadReport&, LoadProgress*,
                         const SceneReadOptions&);
using PathReader = Scene (*)(const std::string&, LoadReport&, LoadProgress*);

// A format parses the file's bytes, or (when its file names others beside it, as SOG's
// meta.json does) reads from the path itself; exactly one of the two is set.
struct FormatReader {
  SceneFormat format;
  Recogniser recognises;
  Parser parse;
  PathReader read = nullptr;
  Declarer declare = nullptr;
};

// Bytes a recogniser may look at: more than any PLY header of a Gaussian scene.
constexpr std::size_t kStartBytes = 64 << 10;

bool ends_with(const std::string& text, std::string_view suffix) {
  if (text.size() < suffix.size()) return false;
  return std::equal(suffix.begin(), suffix.end(), text.end() - static_cast<std::ptrdiff_t>(suffix.size()),
                    [](char a, char b) { return a == std::tolower(static_cast<unsigned char>(b)); });
}

bool starts_as_ply(const FileStart& f) {
  return f.bytes.size() >= 4 && f.bytes.compare(0, 3, "ply") == 0 && (f.bytes[3] == '\n' || f.bytes[3] == '\r');
}

// The header, as far as the first bytes hold it (the parser checks it properly).
std::string_view ply_header_text(const FileStart& f) {
  const std::size_t end = f.bytes.find("end_header");
  return f.bytes.substr(0, end == std::string_view::npos ? f.bytes.size() : end);
}

bool is_compressed_ply(const FileStart& f) {
  if (!starts_as_ply(f)) return false;
  const std::string_view header = ply_header_text(f);
  return header.find("\nelement chunk ") != std::string_view::npos &&
         header.find(" packed_position") != std::string_view::npos;
}

// Any other PLY: the INRIA reader says what is missing when it is not a Gaussian scene.
bool is_ply(const FileStart& f) { return starts_as_ply(f); }

// .splat has no magic number: the extension decides, and its parser checks the size.
bool is_splat(const FileStart& f) { return ends_with(f.name, ".splat"); }
// .ksplat has a version in its first bytes but no magic number: the extension decides.
bool is_ksplat(const FileStart& f) { return ends_with(f.name, ".ksplat"); }

Scene parse_inria_ply(const char* data, std::size_t size, const std::string& name, LoadReport& report,
                      LoadProgress* progress, const SceneReadOptions&) {
  return parse_ply(data, size, name, &report, progress);
}

bool is_spz(const FileStart& f) { return looks_like_spz(f.bytes.data(), f.bytes.size()); }

Scene parse_spz_file(const char* data, std::size_t size, const std::string& name, LoadReport& report,
                     LoadProgress* progress, const SceneReadOptions& options) {
  return parse_spz(data, size, name, &report, progress, options.spz_axes);
}

// A parser that has no choice to take from the options.
template <Scene (*parse)(const char*, std::size_t, const std::string&, LoadReport&, LoadProgress*)>
Scene without_options(const char* data, std::size_t size, const std::string& name, LoadReport& report,
                      LoadProgress* progress, const SceneReadOptions&) {
  return parse(data, size, name, report, progress);
}

// A SOG meta.json (one chunk) or lod-meta.json (a LOD set), by their keys.
bool is_sog(const FileStart& f) {
  const std::string text(f.bytes);
  return looks_like_sog_meta(text) || looks_like_sog_lod_meta(text);
}

// A SOG bundle: a zip archive (SuperSplat's .sog export) holding meta.json and its textures.
bool is_zip(const FileStart& f) { return looks_like_zip(f.bytes.data(), f.bytes.size()); }

Scene parse_sog_bundle(const char* data, std::size_t size, const std::string& name, LoadReport& report,
                       LoadProgress* progress, const SceneReadOptions&) {
  const ZipReader zip(data, size, name);
  if (!zip.contains("meta.json"))
    throw Error(name + ": a zip archive without meta.json: not a SOG bundle (expected a PLY, .splat, .ksplat, .spz or SOG)");
  const std::vector<char> meta = zip.read("meta.json", kMaxSogJsonBytes);
  const SogFileSource files = [&zip](const std::string& file) { return zip.read(file, kMaxSogTextureBytes); };
  return parse_sog(std::string(meta.begin(), meta.end()), files, name, &report, progress);
}

Scene read_sog_file(const std::string& path, LoadReport& report, LoadProgress* progress) {
  const std::vector<char> text = read_regular_file(path, kMaxSogJsonBytes);
  return parse_sog_file(text.data(), text.size(), path, &report, progress);
}

DeclaredScene declare_ply_file(const FileStart& f, std::uint64_t file_size) {
  return declare_ply(f.bytes.data(), f.bytes.size(), file_size, f.name);
}
DeclaredScene declare_spz_file(const FileStart& f, std::uint64_t) {
  return declare_spz(f.bytes.data(), f.bytes.size(), f.name);
}
DeclaredScene declare_splat_file(const FileStart& f, std::uint64_t file_size) {
  return declare_splat(file_size, f.name);
}

// In order: formats with a magic number or header first, extension-only formats last.
const FormatReader kReaders[] = {
    {SceneFormat::compressed_ply, is_compressed_ply, without_options<parse_compressed_ply>, nullptr, declare_ply_file},
    {SceneFormat::inria_ply, is_ply, parse_inria_ply, nullptr, declare_ply_file},
    {SceneFormat::spz, is_spz, parse_spz_file, nullptr, declare_spz_file},
    {SceneFormat::sog, is_sog, nullptr, read_sog_file},
    {SceneFormat::sog_bundle, is_zip, parse_sog_bundle},
    {SceneFormat::splat, is_splat, without_options<parse_splat>, nullptr, declare_splat_file},
    {SceneFormat::ksplat, is_ksplat, without_options<parse_ksplat>},
};

double seconds_since(std::chrono::steady_clock::time_point began) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - began).count();
}

// "it starts with "GIF89a"", or "it is empty".
std::string describe_start(const FileStart& f) {
  if (f.bytes.empty()) return "it is empty";
  return "it starts with \"" + printable_file_text(f.bytes.substr(0, 8)) + "\"";
}

// The first reader that recognises the file; throws the one "not a scene file" line otherwise.
const FormatReader& recognise(const FileStart& start) {
  for (const FormatReader& reader : kReaders)
    if (reader.recognises(start)) return reader;
  throw Error(start.name + ": not a scene file: " + describe_start(start) + "; expected a PLY, .splat, .ksplat, .spz or SOG");
}

void note_format(LoadReport& report, SceneFormat format) {
  report.format = format_name(format);
  report.quantisation = format_quantisation(format);
}

}  // namespace

const char* format_name(SceneFormat format) {
  switch (format) {
    case SceneFormat::inria_ply: return "INRIA PLY";
    case SceneFormat::compressed_ply: return "PlayCanvas compressed PLY";
    case SceneFormat::splat: return ".splat (antimatter15)";
    case SceneFormat::spz: return "SPZ (Niantic)";
    case SceneFormat::sog: return "SOG (PlayCanvas)";
    case SceneFormat::sog_bundle: return "SOG (PlayCanvas), zipped";
    case SceneFormat::ksplat: return ".ksplat (GaussianSplats3D)";
  }
  return "unknown";
}

const char* format_quantisation(SceneFormat format) {
  switch (format) {
    case SceneFormat::inria_ply: return "none: float or double per value";
    case SceneFormat::compressed_ply:
      return "11-10-11 positions and log-scales and 8-8-8-8 colour and opacity in 256-Gaussian chunks (min/max), "
             "2-10-10-10 smallest-three rotations, 8-bit SH";
    case SceneFormat::splat:
      return "float positions and scales, 8-bit colour, opacity and rotation components; no SH bands";
    case SceneFormat::spz: return "fixed-point positions, 8-bit scales, rotations, colours, opacity and SH";
    case SceneFormat::sog:
    case SceneFormat::sog_bundle:
      return "16-bit positions, 8-bit quaternions, codebook scales, colours and SH in WebP textures";
    case SceneFormat::ksplat:
      return "per section: float, half or 8-bit positions, scales, rotations, colours and SH";
  }
  return "";
}

Scene parse_scene_bytes(const char* data, std::size_t size, const std::string& name, LoadReport* report,
                        LoadProgress* progress, const SceneReadOptions& options) {
  LoadReport local_report;
  if (!report) report = &local_report;
  // A JSON object may hold its keys past kStartBytes; its bytes are already in memory.
  const std::size_t start_size =
      may_be_json_object(std::string_view(data, std::min(size, kStartBytes))) ? kMaxSogJsonBytes : kStartBytes;
  const FormatReader& reader = recognise({name, std::string_view(data, std::min(size, start_size))});
  if (!reader.parse)
    throw Error(name + ": " + format_name(reader.format) + " reads the files beside this one: open it by its path");
  const auto began = std::chrono::steady_clock::now();
  Scene scene = reader.parse(data, size, name, *report, progress, options);
  report->decode_seconds = seconds_since(began);
  note_format(*report, reader.format);
  return scene;
}

namespace {

std::uint64_t file_size_of(const std::string& path) {
  std::error_code error;
  const auto size = std::filesystem::file_size(path, error);
  return error ? 0 : static_cast<std::uint64_t>(size);
}

// The file's start recognised and its header checked against its size, before it is read whole.
SceneDeclaration declare(const std::string& path, const FormatReader** reader_out) {
  const std::vector<char> start = read_recognition_start(path, kStartBytes);
  const FileStart file_start{path, std::string_view(start.data(), start.size())};
  const FormatReader& reader = recognise(file_start);
  if (reader_out) *reader_out = &reader;
  SceneDeclaration out;
  out.format = reader.format;
  out.file_bytes = file_size_of(path);
  // A size below what was read is no size (files of /proc report 0): the full read checks all.
  if (!reader.declare || out.file_bytes < start.size()) return out;
  const DeclaredScene declared = reader.declare(file_start, out.file_bytes);
  out.gaussians = declared.gaussians;
  out.sh_degree = declared.sh_degree;
  const std::uint64_t scene_bytes = sizeof(float) * (14 + 3 * std::uint64_t(sh_coefficient_count(out.sh_degree) - 1));
  out.load_bytes = out.file_bytes + out.gaussians * (scene_bytes + declared.extra_bytes_per_gaussian);
  return out;
}

Scene load_recognised(const std::string& path, const FormatReader& reader, LoadReport& report, LoadProgress* progress,
                      const SceneReadOptions& options) {
  const auto began = std::chrono::steady_clock::now();
  if (reader.read) {  // reading and decoding interleave: all of it counts as decoding
    Scene scene = reader.read(path, report, progress);
    report.decode_seconds = seconds_since(began);
    note_format(report, reader.format);
    return scene;
  }
  const std::vector<char> bytes = read_regular_file(path, std::numeric_limits<std::size_t>::max(), progress);
  const double read_seconds = seconds_since(began);
  Scene scene = parse_scene_bytes(bytes.data(), bytes.size(), path, &report, progress, options);
  report.read_seconds = read_seconds;
  return scene;
}

}  // namespace

SceneDeclaration declare_scene_file(const std::string& path) { return declare(path, nullptr); }

Scene load_scene_file(const std::string& path, LoadReport* report, LoadProgress* progress,
                      const SceneReadOptions& options) {
  LoadReport local_report;
  if (!report) report = &local_report;
  // Recognised from its start first: a file of no known format is not read whole, nor one
  // whose header contradicts its size or whose declared Gaussians cannot fit in memory.
  const FormatReader* reader = nullptr;
  const SceneDeclaration declared = declare(path, &reader);
  const std::string name = printable_file_text(path, kMaxPrintedPathBytes);
  const AvailableMemory available = available_host_memory();
  if (available.bytes > 0 && declared.load_bytes > available.bytes)
    throw Error(name + ": " + std::to_string(declared.gaussians) + " Gaussians in " +
                format_bytes(declared.file_bytes) + " need about " + format_bytes(declared.load_bytes) +
                " of memory to load, but " + format_bytes(available.bytes) + " is available (" +
                available.limited_by + ")");
  try {
    return load_recognised(path, *reader, *report, progress, options);
  } catch (const std::bad_alloc&) {
    throw Error(name + ": out of memory while loading it (" + format_bytes(declared.file_bytes) + " of file" +
                (declared.gaussians ? ", " + std::to_string(declared.gaussians) + " Gaussians declared" : "") +
                "; " + format_bytes(available.bytes) + " was available)");
  }
}

bool parse_spz_axes(const std::string& text, SpzAxes& out) {
  if (text == "niantic") out = SpzAxes::niantic;
  else if (text == "none") out = SpzAxes::none;
  else return false;
  return true;
}

namespace {

void write_inria_ply(const Scene& scene, const std::string& path, const SceneWriteOptions&) { save_ply(scene, path); }
void write_splat(const Scene& scene, const std::string& path, const SceneWriteOptions&) { save_splat(scene, path); }

// Longer name endings first: ".compressed.ply" before ".ply".
const WritableFormat kWriters[] = {
    {SceneFormat::compressed_ply, ".compressed.ply", save_compressed_ply, 3, true},
    {SceneFormat::inria_ply, ".ply", write_inria_ply, 3, true},
    {SceneFormat::splat, ".splat", write_splat, 0, false},
    {SceneFormat::spz, ".spz", save_spz, 3, true},
    {SceneFormat::sog_bundle, ".sog", save_sog_bundle, 3, true},
    {SceneFormat::sog, "meta.json", save_sog_folder, 3, true},
};

}  // namespace

const WritableFormat* writable_format_for(const std::string& path) {
  for (const WritableFormat& format : kWriters)
    if (ends_with(path, format.name_ending)) return &format;
  return nullptr;
}

const char* writable_scene_extensions() {
  return ".ply (INRIA PLY), .compressed.ply, .splat, .spz, .sog (zipped SOG) or meta.json (SOG, textures beside it)";
}

void save_scene_file(const Scene& scene, const std::string& path, const SceneWriteOptions& options) {
  const WritableFormat* format = writable_format_for(path);
  if (!format) throw Error(path + ": unknown scene format (the name picks it: " + writable_scene_extensions() + ")");
  format->write(scene, path, options);
}

}  // namespace flashgs
