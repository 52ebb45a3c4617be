// Where the widgets that tests click are on screen (--log-input): each logs its centre once per
// move, so a test clicks the widget itself and not a place that a longer path or a font moves.
#pragma once

namespace flashgs::viewer {

void set_widget_place_logging(bool on);

// After an ImGui item: logs `widget "NAME" at X,Y` (window coordinates, the cursor's) when its place changed.
void note_widget_place(const char* name);
// The same for something drawn outside ImGui's items (the status line), given its corners.
void note_drawn_place(const char* name, float x0, float y0, float x1, float y1);

}  // namespace flashgs::viewer
