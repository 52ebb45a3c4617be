// flashgs.RenderOptions and flashgs.SplatKernel: every switch of options.h's kRenderSwitches
// table as an attribute of its label, the kernel ("auto" = the scene's), tau, background, SH cap
// and the fp16 options, each checked as the CLI checks its flag.
#include <cmath>
#include <string>

#include <pybind11/stl.h>

#include "bindings.h"
#include "flashgs/error.h"

namespace flashgs::python {

namespace {

// The range the CLI's --tau takes.
constexpr double kMinTau = 1e-6, kMaxTau = 0.99;

std::string value_text(py::handle value) { return py::repr(value); }

bool bool_value(py::handle value, const std::string& name) {
  if (!py::isinstance<py::bool_>(value)) throw Error(name + ": expected True or False, got " + value_text(value));
  return value.cast<bool>();
}

double number_in(py::handle value, const std::string& name, double low, double high) {
  if (py::isinstance<py::bool_>(value) || py::isinstance<py::str>(value) || !PyNumber_Check(value.ptr()))
    throw Error(name + ": expected a number, got " + value_text(value));
  const double v = py::float_(py::reinterpret_borrow<py::object>(value)).cast<double>();
  if (!std::isfinite(v)) throw Error(name + ": " + value_text(value) + " is not a finite number");
  if (v < low || v > high)
    throw Error(name + ": " + value_text(value) + " is outside [" + py::repr(py::float_(low)).cast<std::string>() +
                ", " + py::repr(py::float_(high)).cast<std::string>() + "]");
  return v;
}

const RenderSwitch* find_switch(const std::string& label) {
  for (const RenderSwitch& s : kRenderSwitches)
    if (label == s.label) return &s;
  return nullptr;
}

// The names RenderOptions takes, in the order help() lists them.
std::vector<std::string> option_names() {
  std::vector<std::string> names = {"algorithm", "kernel", "tau", "background", "sh_degree"};
  for (const RenderSwitch& s : kRenderSwitches) names.emplace_back(s.label);
  for (const char* name : {"fp16_sh", "fp16_shape", "fp16_blend", "collect_tile_counts"}) names.emplace_back(name);
  return names;
}

// Sets the option `name` from a Python value: the one place each option is checked.
void set_option(PyRenderOptions& o, const std::string& name, py::handle value) {
  RenderOptions& r = o.options;
  if (const RenderSwitch* s = find_switch(name)) {
    r.*(s->member) = bool_value(value, name);
  } else if (name == "algorithm") {
    const std::string text = py::isinstance<py::str>(value) ? value.cast<std::string>() : "";
    if (text != "flash" && text != "baseline")
      throw Error("algorithm: expected \"flash\" or \"baseline\", got " + value_text(value));
    r.algorithm = text == "flash" ? Algorithm::flash : Algorithm::baseline;
  } else if (name == "kernel") {
    o.kernel_auto = py::isinstance<py::str>(value) && value.cast<std::string>() == "auto";
    if (!o.kernel_auto) r.kernel = kernel_from(value, "kernel");
  } else if (name == "tau") {
    r.tau = static_cast<float>(number_in(value, name, kMinTau, kMaxTau));
  } else if (name == "background") {
    if (py::isinstance<py::str>(value) || !py::isinstance<py::sequence>(value) || py::len(value) != 3)
      throw Error("background: expected three numbers r, g, b in [0, 1], got " + value_text(value));
    const py::sequence rgb = py::reinterpret_borrow<py::sequence>(value);
    for (int k = 0; k < 3; ++k) r.background[k] = static_cast<float>(number_in(rgb[k], name, 0.0, 1.0));
  } else if (name == "sh_degree") {
    if (!py::isinstance<py::int_>(value) || py::isinstance<py::bool_>(value))
      throw Error("sh_degree: expected a whole number 0-3, got " + value_text(value));
    r.sh_degree_cap = static_cast<int>(number_in(value, name, 0, 3));
  } else if (name == "fp16_sh") {
    r.fp16_sh = bool_value(value, name);
  } else if (name == "fp16_shape") {
    r.fp16_shape = bool_value(value, name);
  } else if (name == "fp16_blend") {
    r.fp16_blend = bool_value(value, name);
  } else if (name == "collect_tile_counts") {
    r.collect_tile_counts = bool_value(value, name);
  } else {
    std::string known;
    for (const std::string& n : option_names()) known += (known.empty() ? "" : ", ") + n;
    throw py::type_error("unknown render option '" + name + "'; the options are " + known);
  }
}

py::object kernel_value(const PyRenderOptions& o) {
  return o.kernel_auto ? py::object(py::str("auto")) : py::cast(o.options.kernel);
}

}  // namespace

PyRenderOptions with_options(const PyRenderOptions& options, const py::kwargs& values) {
  PyRenderOptions o = options;
  for (auto item : values) set_option(o, item.first.cast<std::string>(), item.second);
  return o;
}

SplatKernel kernel_from(py::handle value, const std::string& what) {
  if (py::isinstance<SplatKernel>(value)) return value.cast<SplatKernel>();
  if (!py::isinstance<py::str>(value))
    throw Error(what + ": expected a SplatKernel or \"classic\", \"antialiased\" or \"antialiased=EPS\", got " +
                value_text(value));
  return parse_splat_kernel(value.cast<std::string>(), what);
}

RenderOptions PyRenderOptions::resolved(const Scene& scene) const {
  RenderOptions r = options;
  if (kernel_auto) r.kernel = scene.trained_kernel.kernel;
  if (r.is_baseline())  // the baseline has every switch off, as RenderOptions::baseline() and the CLI
    for (const RenderSwitch& s : kRenderSwitches) r.*(s.member) = RenderOptions::baseline().*(s.member);
  return r;
}

void bind_options(py::module_& m) {
  py::class_<SplatKernel>(m, "SplatKernel", "The screen-space footprint model a scene is drawn with.")
      .def_static("classic", &SplatKernel::classic, "3DGS's kernel: 0.3 px^2 added, opacity unchanged.")
      .def_static("antialiased", &SplatKernel::antialiased, py::arg("epsilon") = kGsplatAntialiasEpsilon,
                  "gsplat's anti-aliased kernel (Mip-Splatting's 2D filter: epsilon 0.1).")
      .def_static("parse", [](const std::string& text) { return parse_splat_kernel(text, "kernel"); },
                  py::arg("text"), "\"classic\", \"antialiased\" or \"antialiased=EPS\".")
      .def_property_readonly("mode", [](const SplatKernel& k) { return k.compensates_opacity() ? "antialiased" : "classic"; })
      .def_property_readonly("epsilon", &SplatKernel::dilation, "px^2 added to the 2D covariance")
      .def_property_readonly("spec", &SplatKernel::spec, "the text form: classic, antialiased or antialiased=EPS")
      .def("__eq__", [](const SplatKernel& a, const SplatKernel& b) { return a == b; })
      .def("__hash__", [](const SplatKernel& k) { return py::hash(py::str(k.spec())); })
      .def("__repr__", [](const SplatKernel& k) { return "SplatKernel.parse(\"" + k.spec() + "\")"; })
      .def("__str__", &SplatKernel::description);

  py::class_<PyRenderOptions> options(m, "RenderOptions",
                                      "How a frame is drawn: the algorithm, each optimisation switch, the kernel, "
                                      "tau, background, SH cap and the fp16 options. Keywords as the attributes.");
  options.def(py::init([](const py::kwargs& values) { return with_options(PyRenderOptions{}, values); }))
      .def_static("names", &option_names, "Every option RenderOptions takes, switches included.")
      .def_static(
          "switches",
          [] {
            py::list rows;
            for (const RenderSwitch& s : kRenderSwitches) {
              py::dict row;
              row["name"] = s.label;
              row["cli_flag"] = std::string("--no-") + s.cli_name;
              row["cpu"] = s.honoured_by(Backend::cpu);
              row["cuda"] = s.honoured_by(Backend::cuda);
              row["changes_pairs"] = s.changes_pairs;
              row["help"] = s.help;
              rows.append(row);
            }
            return rows;
          },
          "The optimisation switches (dicts: name, cli_flag, cpu, cuda, changes_pairs, help), each on by default.")
      .def_property_readonly("label", [](const PyRenderOptions& o) { return o.options.label(); },
                             "a short label such as \"flash\" or \"flash-no_tight_bbox\" (kernel \"auto\" as classic)")
      .def("replace", &with_options, "A copy with the options given changed.")
      .def("__eq__", [](const PyRenderOptions& a, const PyRenderOptions& b) {
        return a.kernel_auto == b.kernel_auto && a.options == b.options;
      })
      .def("__repr__", [](const PyRenderOptions& o) {
        return "<flashgs.RenderOptions " + o.options.label() + ", kernel " +
               (o.kernel_auto ? std::string("auto") : o.options.kernel.spec()) + ">";
      });
  options.def_property(
      "algorithm", [](const PyRenderOptions& o) { return algorithm_name(o.options.algorithm); },
      [](PyRenderOptions& o, py::handle v) { set_option(o, "algorithm", v); }, "\"flash\" or \"baseline\"");
  options.def_property("kernel", &kernel_value, [](PyRenderOptions& o, py::handle v) { set_option(o, "kernel", v); },
                       "\"auto\" (the scene's trained kernel), a SplatKernel or its text");
  options.def_property(
      "tau", [](const PyRenderOptions& o) { return o.options.tau; },
      [](PyRenderOptions& o, py::handle v) { set_option(o, "tau", v); }, "alpha below which a Gaussian adds nothing");
  options.def_property(
      "background",
      [](const PyRenderOptions& o) {
        return py::make_tuple(o.options.background[0], o.options.background[1], o.options.background[2]);
      },
      [](PyRenderOptions& o, py::handle v) { set_option(o, "background", v); }, "r, g, b in [0, 1]");
  options.def_property(
      "sh_degree", [](const PyRenderOptions& o) { return o.options.sh_degree_cap; },
      [](PyRenderOptions& o, py::handle v) { set_option(o, "sh_degree", v); }, "use at most this many SH bands (0-3)");
  for (const RenderSwitch& s : kRenderSwitches) {
    const SwitchMember member = s.member;
    const std::string name = s.label;
    options.def_property(
        s.label, [member](const PyRenderOptions& o) { return o.options.*member; },
        [name](PyRenderOptions& o, py::handle v) { set_option(o, name, v); }, s.help);
  }
  const std::pair<const char*, bool RenderOptions::*> precision[] = {
      {"fp16_sh", &RenderOptions::fp16_sh},
      {"fp16_shape", &RenderOptions::fp16_shape},
      {"fp16_blend", &RenderOptions::fp16_blend},
      {"collect_tile_counts", &RenderOptions::collect_tile_counts}};
  for (const auto& [label, member] : precision) {
    const std::string name = label;
    const auto field = member;
    options.def_property(
        label, [field](const PyRenderOptions& o) { return o.options.*field; },
        [name](PyRenderOptions& o, py::handle v) { set_option(o, name, v); });
  }
}

}  // namespace flashgs::python
