// x11_drop: drops a file on the window under (x, y) through the XDND protocol, as a file manager does (viewer test helper).
#include <X11/Xlib.h>
#include <X11/Xatom.h>
#include <unistd.h>

#include <cstdio>
#include <cstdlib>
#include <cstring>

// The deepest window under (x, y) that declares XdndAware (GLFW sets it on its windows).
static Window find_aware(Display* d, int x, int y, Atom aware) {
  Window root = DefaultRootWindow(d), child, found = 0;
  int cx, cy;
  Window cur = root;
  while (cur) {
    Atom type; int fmt; unsigned long n, after; unsigned char* data = NULL;
    if (XGetWindowProperty(d, cur, aware, 0, 1, False, AnyPropertyType, &type, &fmt, &n, &after, &data) == Success && type != None) found = cur;
    if (data) XFree(data);
    if (!XTranslateCoordinates(d, root, cur, x, y, &cx, &cy, &child) || !child) break;
    cur = child;
  }
  return found;
}

int main(int argc, char** argv) {
  if (argc < 4) { fprintf(stderr, "usage: dnd X Y FILE\n"); return 2; }
  int x = atoi(argv[1]), y = atoi(argv[2]);
  char uri[4096];
  snprintf(uri, sizeof uri, "file://%s\r\n", argv[3]);
  Display* d = XOpenDisplay(NULL);
  if (!d) return 1;
  Atom aware = XInternAtom(d, "XdndAware", False), enter = XInternAtom(d, "XdndEnter", False),
       position = XInternAtom(d, "XdndPosition", False), status = XInternAtom(d, "XdndStatus", False),
       drop = XInternAtom(d, "XdndDrop", False),
       finished = XInternAtom(d, "XdndFinished", False), selection = XInternAtom(d, "XdndSelection", False),
       uri_list = XInternAtom(d, "text/uri-list", False), copy = XInternAtom(d, "XdndActionCopy", False);
  Window src = XCreateSimpleWindow(d, DefaultRootWindow(d), 0, 0, 1, 1, 0, 0, 0);
  XSetSelectionOwner(d, selection, src, CurrentTime);
  Window target = find_aware(d, x, y, aware);
  if (!target) { fprintf(stderr, "no XdndAware window at %d,%d\n", x, y); return 3; }
  XEvent e;
  memset(&e, 0, sizeof e);
  e.xclient.type = ClientMessage; e.xclient.display = d; e.xclient.window = target; e.xclient.format = 32;
  e.xclient.message_type = enter; e.xclient.data.l[0] = (long)src; e.xclient.data.l[1] = 5L << 24;
  e.xclient.data.l[2] = (long)uri_list;
  XSendEvent(d, target, False, NoEventMask, &e);
  e.xclient.message_type = position; e.xclient.data.l[1] = 0; e.xclient.data.l[2] = (x << 16) | y;
  e.xclient.data.l[3] = CurrentTime; e.xclient.data.l[4] = (long)copy;
  XSendEvent(d, target, False, NoEventMask, &e);
  XFlush(d);
  int dropped = 0;
  // Enter + Position sent; on the target's Status we send Drop, answer its request for the
  // text/uri-list selection, and finish on its Finished (up to about 20 s).
  for (int i = 0; i < 400; ++i) {
    while (XPending(d)) {
      XNextEvent(d, &e);
      if (e.type == ClientMessage && e.xclient.message_type == status && !dropped) {
        XEvent m; memset(&m, 0, sizeof m);
        m.xclient.type = ClientMessage; m.xclient.display = d; m.xclient.window = target; m.xclient.format = 32;
        m.xclient.message_type = drop; m.xclient.data.l[0] = (long)src; m.xclient.data.l[2] = CurrentTime;
        XSendEvent(d, target, False, NoEventMask, &m); XFlush(d);
        dropped = 1;
      } else if (e.type == SelectionRequest) {
        XSelectionRequestEvent* r = &e.xselectionrequest;
        XChangeProperty(d, r->requestor, r->property, r->target, 8, PropModeReplace, (unsigned char*)uri, (int)strlen(uri));
        XEvent n; memset(&n, 0, sizeof n);
        n.xselection.type = SelectionNotify; n.xselection.display = d; n.xselection.requestor = r->requestor;
        n.xselection.selection = r->selection; n.xselection.target = r->target; n.xselection.property = r->property;
        n.xselection.time = r->time;
        XSendEvent(d, r->requestor, False, NoEventMask, &n); XFlush(d);
      } else if (e.type == ClientMessage && e.xclient.message_type == finished) {
        printf("drop finished\n");
        XCloseDisplay(d);
        return 0;
      }
    }
    usleep(50000);
  }
  fprintf(stderr, "no XdndFinished (dropped=%d)\n", dropped);
  return 4;
}
