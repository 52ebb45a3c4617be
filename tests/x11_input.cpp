// x11_input: a user's mouse and keyboard through the XTEST extension, and a window manager's close request (viewer test helper).
//
//   x11_input move X Y          pointer to (X, Y) on the root window
//   x11_input down|up button    left button pressed / released (button2: middle, button3: right)
//   x11_input down|up KEYSYM    key pressed / released (X keysym name: Control_L, Return, space, F12)
//   x11_input type TEXT         each character of TEXT pressed and released
//   x11_input close X Y         WM_DELETE_WINDOW to the top-level window at (X, Y)
//   x11_input focus X Y         keyboard focus to the top-level window at (X, Y)
//
// Only single events: holding across the viewer's frames is the calling script's job (it
// waits for the viewer's --log-input lines between down and up).
#include <X11/Xatom.h>
#include <X11/Xlib.h>
#include <X11/extensions/XTest.h>

#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>

#include <unistd.h>

namespace {

bool send_key(Display* d, const char* name, bool down) {
  const KeySym sym = XStringToKeysym(name);
  const KeyCode code = sym == NoSymbol ? 0 : XKeysymToKeycode(d, sym);
  if (!code) {
    std::fprintf(stderr, "x11_input: no key for \"%s\"\n", name);
    return false;
  }
  XTestFakeKeyEvent(d, code, down ? True : False, CurrentTime);
  return true;
}

// The root's child (a top-level window: no window manager runs on Xvfb) under (x, y).
::Window top_level_at(Display* d, int x, int y) {
  ::Window root = DefaultRootWindow(d), child = 0;
  int cx = 0, cy = 0;
  if (!XTranslateCoordinates(d, root, root, x, y, &cx, &cy, &child)) return 0;
  return child;
}

// The top-level window at (x, y), waiting for it to be mapped there (up to 10 s: it may still
// be on its way to the screen on a loaded machine), or 0 with a line saying so.
::Window wait_for_top_level_at(Display* d, int x, int y) {
  ::Window target = top_level_at(d, x, y);
  for (int attempt = 0; !target && attempt < 200; ++attempt) {
    usleep(50000);
    XSync(d, False);
    target = top_level_at(d, x, y);
  }
  if (!target) std::fprintf(stderr, "x11_input: no window at %d,%d\n", x, y);
  return target;
}

// What a window manager does when the user clicks a window. Without one (Xvfb), the window has
// the focus only if GLFW's own request when it showed it found it mapped (GLFW waits 0.1 s for
// that); otherwise keys go to the window under the pointer, which may be the root.
bool focus_window(Display* d, int x, int y) {
  const ::Window target = wait_for_top_level_at(d, x, y);
  if (!target) return false;
  XSetInputFocus(d, target, RevertToParent, CurrentTime);
  return true;
}

bool close_window(Display* d, int x, int y) {
  const ::Window target = wait_for_top_level_at(d, x, y);
  if (!target) return false;
  XEvent e;
  std::memset(&e, 0, sizeof e);
  e.xclient.type = ClientMessage;
  e.xclient.window = target;
  e.xclient.message_type = XInternAtom(d, "WM_PROTOCOLS", False);
  e.xclient.format = 32;
  e.xclient.data.l[0] = static_cast<long>(XInternAtom(d, "WM_DELETE_WINDOW", False));
  e.xclient.data.l[1] = CurrentTime;
  XSendEvent(d, target, False, NoEventMask, &e);
  return true;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 2) {
    std::fprintf(stderr, "usage: x11_input move X Y | down|up button|KEYSYM | type TEXT | close X Y | focus X Y\n");
    return 2;
  }
  Display* d = XOpenDisplay(nullptr);
  if (!d) return 1;
  int event_base = 0, error_base = 0, major = 0, minor = 0;
  if (!XTestQueryExtension(d, &event_base, &error_base, &major, &minor)) {
    std::fprintf(stderr, "the X server has no XTEST extension\n");
    return 3;
  }
  const std::string verb = argv[1];
  bool ok = true;
  if (verb == "move" && argc == 4) {
    XTestFakeMotionEvent(d, -1, std::atoi(argv[2]), std::atoi(argv[3]), CurrentTime);
  } else if ((verb == "down" || verb == "up") && argc == 3) {
    const std::string what = argv[2];
    if (what == "button" || what == "button2" || what == "button3")
      XTestFakeButtonEvent(d, what == "button" ? 1 : what[6] - '0', verb == "down" ? True : False, CurrentTime);
    else ok = send_key(d, argv[2], verb == "down");
  } else if (verb == "type" && argc == 3) {
    for (const char* c = argv[2]; *c && ok; ++c) {
      const char name[2] = {*c, 0};
      ok = send_key(d, name, true) && send_key(d, name, false);
    }
  } else if (verb == "close" && argc == 4) {
    ok = close_window(d, std::atoi(argv[2]), std::atoi(argv[3]));
  } else if (verb == "focus" && argc == 4) {
    ok = focus_window(d, std::atoi(argv[2]), std::atoi(argv[3]));
  } else {
    std::fprintf(stderr, "x11_input: bad arguments\n");
    ok = false;
  }
  XSync(d, False);
  XCloseDisplay(d);
  return ok ? 0 : 4;
}
