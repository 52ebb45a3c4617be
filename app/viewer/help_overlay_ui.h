// The help window (F1): the table of every key and mouse shortcut, and the small hint left on screen while the panels are hidden.
#pragma once

namespace flashgs::viewer {

struct Shortcut {
  const char* keys;
  const char* action;
};

// Every shortcut of the viewer, in the order the help window lists them (the frame loop's
// key handling in viewer_app_gl.cpp is the other side of this table).
inline constexpr Shortcut kShortcuts[] = {
    {"left-drag", "look around (fly) / orbit about the pivot (orbit)"},
    {"right/middle-drag, Shift+left", "pan"},
    {"wheel", "dolly toward / away from the view"},
    {"W A S D, Q E", "move (fly) or dolly (orbit, W/S); down / up along the world up"},
    {"Shift (held)", "move four times faster"},
    {"+ / -, Ctrl+wheel", "movement speed x1.25 / x0.8"},
    {"O", "fly / orbit navigation"},
    {"F", "frame the whole scene"},
    {"N / P", "next / previous training camera"},
    {"Space", "play / stop the path through the cameras"},
    {"I", "add the view as a key of the camera path"},
    {"Ctrl+S", "save the camera path (its file in the Camera path section)"},
    {"click a frustum", "jump to that training camera (frustums on)"},
    {"G", "ground grid and axes"},
    {"B", "baseline / flash (all optimisations)"},
    {"K", "next kernel: classic, anti-aliased (gsplat), anti-aliased (Mip-Splatting)"},
    {"C", "compare two configurations for this view"},
    {"H", "tile heat map (pairs per tile)"},
    {"V", "view: colour, blended depth, Gaussians blended per pixel"},
    {"F12 / Shift+F12", "screenshot of the render / of the whole window"},
    {"Ctrl+O, or drop a file", "open a scene (PLY, folder or 3DGS output)"},
    {"Tab", "hide / show the panels"},
    {"F1", "this help"},
    {"Esc", "close an open list; else asks, and Esc again quits"},
    {"Ctrl+Q", "quit"},
};

// The help window while `*open`; its close button clears it.
void draw_help_window(bool* open, float ui_scale);
// A one-line hint in a corner while the panels are hidden.
void draw_hidden_panels_hint(float ui_scale);

}  // namespace flashgs::viewer
