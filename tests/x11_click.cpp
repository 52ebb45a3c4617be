// x11_click: moves the pointer to (x, y) on the root window and clicks the left button there
// through the XTEST extension, as a user's mouse does (viewer test helper).
#include <X11/Xlib.h>
#include <X11/extensions/XTest.h>
#include <unistd.h>

#include <cstdio>
#include <cstdlib>

int main(int argc, char** argv) {
  if (argc < 3) {
    std::fprintf(stderr, "usage: x11_click X Y\n");
    return 2;
  }
  Display* d = XOpenDisplay(nullptr);
  if (!d) return 1;
  int event_base = 0, error_base = 0, major = 0, minor = 0;
  if (!XTestQueryExtension(d, &event_base, &error_base, &major, &minor)) {
    std::fprintf(stderr, "the X server has no XTEST extension\n");
    return 3;
  }
  // Move first and let the window see the pointer enter, then press and release a little
  // later: the viewer must see the button down for at least one frame.
  XTestFakeMotionEvent(d, -1, std::atoi(argv[1]), std::atoi(argv[2]), CurrentTime);
  XFlush(d);
  usleep(300000);
  XTestFakeButtonEvent(d, 1, True, CurrentTime);
  XFlush(d);
  usleep(150000);
  XTestFakeButtonEvent(d, 1, False, CurrentTime);
  XFlush(d);
  XCloseDisplay(d);
  return 0;
}
