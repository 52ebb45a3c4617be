// Where the widgets that tests click are on screen (--log-input): each logs its centre once per
// move, so a test clicks the widget itself and not a place that a longer path or a font moves.
#pragma once

namespace flashgs::viewer {

void set_widget_place_logging(bool on);

// After an ImGui item: logs `widget "NAME" at X,Y` (window coordinates, the cursor's) when its place changed.
void note_widget_place(const char* name);

}  // namespace flashgs::viewer
