// SVG plot of error against run time (see report_plot.h).
#include "report_plot.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>

namespace flashgs::cli {
namespace {

// PSNR of identical images is infinite; plotted at the top of the axis.
double plotted_psnr(const SweepResult& r, double cap) {
  return std::isfinite(r.vs_reference.psnr_db) ? std::min(r.vs_reference.psnr_db, cap) : cap;
}

// "Nice" tick step (1, 2 or 5 times a power of ten) for about `count` ticks over the range.
double tick_step(double lo, double hi, int count) {
  const double raw = (hi - lo) / std::max(1, count);
  const double power = std::pow(10.0, std::floor(std::log10(raw)));
  for (double m : {1.0, 2.0, 5.0, 10.0})
    if (m * power >= raw) return m * power;
  return 10 * power;
}

std::string escape(const std::string& text) {
  std::string out;
  for (char ch : text) {
    if (ch == '<') out += "&lt;";
    else if (ch == '>') out += "&gt;";
    else if (ch == '&') out += "&amp;";
    else out += ch;
  }
  return out;
}

const char* group_colour(const std::string& group) {
  static const std::map<std::string, const char*> colours = {
      {"baseline", "#d62728"}, {"flash", "#1f77b4"},    {"alone", "#2ca02c"},       {"left out", "#ff7f0e"},
      {"tau", "#9467bd"},      {"gpu alone", "#8c564b"}, {"gpu left out", "#e377c2"}, {"precision", "#17becf"},
      {"kernel", "#bcbd22"}};
  auto it = colours.find(group);
  return it == colours.end() ? "#7f7f7f" : it->second;
}

}  // namespace

std::vector<std::size_t> pareto_front(const std::vector<SweepResult>& results) {
  std::vector<std::size_t> front;
  for (std::size_t i = 0; i < results.size(); ++i) {
    bool dominated = false;
    for (std::size_t j = 0; j < results.size() && !dominated; ++j) {
      if (i == j) continue;
      const double ti = results[i].median_ms, tj = results[j].median_ms;
      const double ei = results[i].vs_reference.psnr_db, ej = results[j].vs_reference.psnr_db;
      dominated = tj <= ti && ej >= ei && (tj < ti || ej > ei);
    }
    if (!dominated) front.push_back(i);
  }
  std::sort(front.begin(), front.end(),
            [&](std::size_t a, std::size_t b) { return results[a].median_ms < results[b].median_ms; });
  return front;
}

std::string plot_svg(const std::vector<SweepResult>& results, const std::string& title, const std::string& subtitle) {
  const double width = 960, height = 600, left = 80, right = 250, top = 74, bottom = 70;
  const double plot_w = width - left - right, plot_h = height - top - bottom;
  double t_lo = 1e300, t_hi = 0, e_lo = 1e300, e_hi = 0, finite_hi = 0;
  for (const SweepResult& r : results) {
    t_lo = std::min(t_lo, r.median_ms);
    t_hi = std::max(t_hi, r.median_ms);
    if (std::isfinite(r.vs_reference.psnr_db)) finite_hi = std::max(finite_hi, r.vs_reference.psnr_db);
  }
  const double cap = finite_hi > 0 ? finite_hi + 10 : 150;  // where "identical" is drawn
  for (const SweepResult& r : results) {
    e_lo = std::min(e_lo, plotted_psnr(r, cap));
    e_hi = std::max(e_hi, plotted_psnr(r, cap));
  }
  if (results.empty()) t_lo = 0, t_hi = 1, e_lo = 0, e_hi = 1;
  // Pad the ranges and snap them to ticks.
  double t_pad = std::max((t_hi - t_lo) * 0.08, t_hi * 0.02 + 1e-6), e_pad = std::max((e_hi - e_lo) * 0.08, 1.0);
  double x0 = std::max(0.0, t_lo - t_pad), x1 = t_hi + t_pad, y0 = e_lo - e_pad, y1 = e_hi + e_pad;
  const double xs = tick_step(x0, x1, 8), ys = tick_step(y0, y1, 6);
  x0 = std::floor(x0 / xs) * xs;
  x1 = std::ceil(x1 / xs) * xs;
  y0 = std::floor(y0 / ys) * ys;
  y1 = std::ceil(y1 / ys) * ys;
  auto px = [&](double t) { return left + (t - x0) / (x1 - x0) * plot_w; };
  auto py = [&](double e) { return top + (1.0 - (e - y0) / (y1 - y0)) * plot_h; };

  std::string svg;
  char buf[1024];
  auto add = [&](const char* fmt, auto... args) {
    std::snprintf(buf, sizeof buf, fmt, args...);
    svg += buf;
  };
  add("<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"%.0f\" height=\"%.0f\" viewBox=\"0 0 %.0f %.0f\" "
      "font-family=\"DejaVu Sans, Helvetica, Arial, sans-serif\">\n",
      width, height, width, height);
  svg += "<rect width=\"100%\" height=\"100%\" fill=\"white\"/>\n";
  add("<text x=\"%.0f\" y=\"28\" font-size=\"18\" font-weight=\"bold\">%s</text>\n", left, escape(title).c_str());
  // The subtitle wraps once at a comma when it would run past the legend (~125 characters).
  std::string line1 = subtitle, line2;
  if (subtitle.size() > 125) {
    const std::size_t cut = subtitle.rfind(", ", 125);
    if (cut != std::string::npos) {
      line1 = subtitle.substr(0, cut + 1);
      line2 = subtitle.substr(cut + 2);
    }
  }
  add("<text x=\"%.0f\" y=\"46\" font-size=\"12\" fill=\"#444\">%s</text>\n", left, escape(line1).c_str());
  if (!line2.empty())
    add("<text x=\"%.0f\" y=\"61\" font-size=\"12\" fill=\"#444\">%s</text>\n", left, escape(line2).c_str());
  // Grid and ticks.
  for (double t = x0; t <= x1 + xs * 0.5; t += xs) {
    add("<line x1=\"%.1f\" y1=\"%.1f\" x2=\"%.1f\" y2=\"%.1f\" stroke=\"#e5e5e5\"/>\n", px(t), top, px(t), top + plot_h);
    add("<text x=\"%.1f\" y=\"%.1f\" font-size=\"11\" text-anchor=\"middle\">%g</text>\n", px(t), top + plot_h + 16, t);
  }
  for (double e = y0; e <= y1 + ys * 0.5; e += ys) {
    add("<line x1=\"%.1f\" y1=\"%.1f\" x2=\"%.1f\" y2=\"%.1f\" stroke=\"#e5e5e5\"/>\n", left, py(e), left + plot_w, py(e));
    add("<text x=\"%.1f\" y=\"%.1f\" font-size=\"11\" text-anchor=\"end\">%g</text>\n", left - 6, py(e) + 4, e);
  }
  add("<rect x=\"%.1f\" y=\"%.1f\" width=\"%.1f\" height=\"%.1f\" fill=\"none\" stroke=\"#333\"/>\n", left, top, plot_w,
      plot_h);
  add("<text x=\"%.1f\" y=\"%.1f\" font-size=\"13\" text-anchor=\"middle\">median frame time (ms)</text>\n",
      left + plot_w / 2, height - 22);
  add("<text x=\"18\" y=\"%.1f\" font-size=\"13\" text-anchor=\"middle\" transform=\"rotate(-90 18 %.1f)\">"
      "PSNR vs fp64 reference (dB, higher is better)</text>\n",
      top + plot_h / 2, top + plot_h / 2);
  bool any_identical = false;
  for (const SweepResult& r : results) any_identical = any_identical || !std::isfinite(r.vs_reference.psnr_db);
  if (any_identical)
    add("<text x=\"%.1f\" y=\"%.1f\" font-size=\"10\" fill=\"#666\">identical to the reference: drawn at %.0f dB</text>\n",
        left + 6, py(cap) - 6, cap);
  // Pareto front, as a staircase: between two front points the better accuracy is only had
  // at the slower time.
  const std::vector<std::size_t> front = pareto_front(results);
  std::string path;
  for (std::size_t k = 0; k < front.size(); ++k) {
    const SweepResult& r = results[front[k]];
    const double x = px(r.median_ms), y = py(plotted_psnr(r, cap));
    if (k == 0) std::snprintf(buf, sizeof buf, "M%.1f,%.1f ", x, y);
    else std::snprintf(buf, sizeof buf, "H%.1f V%.1f ", x, y);
    path += buf;
  }
  if (!front.empty()) {  // extend to the right edge: nothing slower improves on the last point
    std::snprintf(buf, sizeof buf, "H%.1f", left + plot_w);
    path += buf;
    add("<path d=\"%s\" fill=\"none\" stroke=\"#111\" stroke-width=\"1.5\" stroke-dasharray=\"6,3\"/>\n", path.c_str());
  }
  // Points, then labels placed where they overlap no earlier label or point (a few candidate
  // positions around each point; the least-overlapping one otherwise).
  struct Box {
    double x0, y0, x1, y1;
  };
  std::vector<Box> taken;
  for (const SweepResult& r : results) {
    const double x = px(r.median_ms), y = py(plotted_psnr(r, cap));
    taken.push_back({x - 6, y - 6, x + 6, y + 6});
  }
  // Drawing order: dominated points, then the front, then baseline and flash on top (an
  // equal-error switch can sit exactly on flash).
  std::vector<std::size_t> order(results.size());
  for (std::size_t i = 0; i < order.size(); ++i) order[i] = i;
  auto layer = [&](std::size_t i) {
    const std::string& g = results[i].config.group;
    if (g == "flash" || g == "baseline") return 2;
    return std::find(front.begin(), front.end(), i) != front.end() ? 1 : 0;
  };
  std::stable_sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) { return layer(a) < layer(b); });
  for (std::size_t i : order) {
    const SweepResult& r = results[i];
    const bool on_front = std::find(front.begin(), front.end(), i) != front.end();
    const double x = px(r.median_ms), y = py(plotted_psnr(r, cap));
    const char* colour = group_colour(r.config.group);
    add("<circle cx=\"%.1f\" cy=\"%.1f\" r=\"%.1f\" fill=\"%s\" stroke=\"%s\" stroke-width=\"1.5\"/>\n", x, y,
        on_front ? 6.0 : 5.0, on_front ? colour : "white", colour);
  }
  for (std::size_t i = 0; i < results.size(); ++i) {
    const SweepResult& r = results[i];
    const double x = px(r.median_ms), y = py(plotted_psnr(r, cap));
    const double w = 5.6 * static_cast<double>(r.config.name.size()), h = 11;
    // (dx, dy) of the label's left baseline corner relative to the point.
    const double candidates[][2] = {{8, 4},       {-8 - w, 4},  {8, -8},       {-8 - w, -8},
                                    {8, 16},      {-8 - w, 16}, {-w / 2, -10}, {-w / 2, 20},
                                    {8, -20},     {-8 - w, -20}, {8, 28},      {-8 - w, 28}};
    double best_overlap = 1e300;
    Box best{};
    for (const auto& c : candidates) {
      Box b{x + c[0], y + c[1] - h + 2, x + c[0] + w, y + c[1] + 2};
      if (b.x0 < left || b.x1 > left + plot_w || b.y0 < top || b.y1 > top + plot_h) continue;
      double overlap = 0;
      for (const Box& t : taken)
        overlap += std::max(0.0, std::min(b.x1, t.x1) - std::max(b.x0, t.x0)) *
                   std::max(0.0, std::min(b.y1, t.y1) - std::max(b.y0, t.y0));
      if (overlap < best_overlap) {
        best_overlap = overlap;
        best = b;
      }
      if (overlap == 0) break;
    }
    if (best_overlap == 1e300) best = {x + 8, y - 7, x + 8 + w, y + 4};
    taken.push_back(best);
    add("<text x=\"%.1f\" y=\"%.1f\" font-size=\"10\" fill=\"%s\">%s</text>\n", best.x0, best.y1 - 2,
        group_colour(r.config.group), escape(r.config.name).c_str());
  }
  // Legend.
  const double lx = left + plot_w + 20;
  double ly = top + 10;
  add("<text x=\"%.1f\" y=\"%.1f\" font-size=\"12\" font-weight=\"bold\">configurations</text>\n", lx, ly);
  std::vector<std::string> groups;
  for (const SweepResult& r : results)
    if (std::find(groups.begin(), groups.end(), r.config.group) == groups.end()) groups.push_back(r.config.group);
  for (const std::string& g : groups) {
    ly += 20;
    add("<circle cx=\"%.1f\" cy=\"%.1f\" r=\"5\" fill=\"%s\"/>\n", lx + 6, ly - 4, group_colour(g));
    add("<text x=\"%.1f\" y=\"%.1f\" font-size=\"12\">%s</text>\n", lx + 18, ly, escape(g).c_str());
  }
  ly += 28;
  add("<line x1=\"%.1f\" y1=\"%.1f\" x2=\"%.1f\" y2=\"%.1f\" stroke=\"#111\" stroke-width=\"1.5\" "
      "stroke-dasharray=\"6,3\"/>\n",
      lx, ly - 4, lx + 24, ly - 4);
  add("<text x=\"%.1f\" y=\"%.1f\" font-size=\"12\">Pareto front</text>\n", lx + 30, ly);
  ly += 18;
  add("<text x=\"%.1f\" y=\"%.1f\" font-size=\"11\" fill=\"#444\">filled: on the front</text>\n", lx, ly);
  ly += 16;
  add("<text x=\"%.1f\" y=\"%.1f\" font-size=\"11\" fill=\"#444\">hollow: dominated</text>\n", lx, ly);
  svg += "</svg>\n";
  return svg;
}

}  // namespace flashgs::cli
