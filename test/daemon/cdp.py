#!/usr/bin/python3
"""Drives a headless Chromium's first page over the Chrome DevTools Protocol.

For the browser tests: Chromium runs with --remote-debugging-port=PORT; each call of this
tool connects to its first page target, does one thing and prints the result.

  cdp.py --port 9222 navigate http://127.0.0.1:8090/
  cdp.py --port 9222 eval 'window.cbloxViewer.blockCount'         # prints the value as JSON
  cdp.py --port 9222 wait 'window.cbloxViewer.complete' --timeout 60
  cdp.py --port 9222 screenshot shot.png

Exit status: 0 done (wait: the expression became truthy), 1 the page threw, timed out or
Chromium was not reachable, 2 usage. Needs Debian's python3-websocket (websocket-client).
"""

import argparse
import base64
import json
import sys
import time
import urllib.request

import websocket


def page_socket(port, timeout_s):
    deadline = time.monotonic() + timeout_s
    last_error = None
    while time.monotonic() < deadline:
        try:
            with urllib.request.urlopen(f"http://127.0.0.1:{port}/json/list", timeout=5) as r:
                targets = json.load(r)
            pages = [t for t in targets if t.get("type") == "page"]
            if pages:
                return websocket.create_connection(pages[0]["webSocketDebuggerUrl"],
                                                   timeout=60, suppress_origin=True)
            last_error = "no page target"
        except OSError as e:
            last_error = str(e)
        time.sleep(0.2)
    raise RuntimeError(f"Chromium's DevTools on port {port} not reachable: {last_error}")


class Page:
    def __init__(self, port, timeout_s=30):
        self.ws = page_socket(port, timeout_s)
        self.next_id = 1

    def call(self, method, **params):
        call_id = self.next_id
        self.next_id += 1
        self.ws.send(json.dumps({"id": call_id, "method": method, "params": params}))
        while True:
            reply = json.loads(self.ws.recv())
            if reply.get("id") != call_id:
                continue  # an event
            if "error" in reply:
                raise RuntimeError(f"{method}: {reply['error']}")
            return reply["result"]

    def evaluate(self, expression):
        result = self.call("Runtime.evaluate", expression=expression, returnByValue=True,
                           awaitPromise=True)
        if "exceptionDetails" in result:
            details = result["exceptionDetails"]
            text = details.get("exception", {}).get("description") or details.get("text")
            raise RuntimeError(f"the page threw: {text}")
        return result["result"].get("value")


def main():
    parser = argparse.ArgumentParser(description=__doc__,
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--port", type=int, required=True)
    parser.add_argument("--timeout", type=float, default=30.0,
                        help="seconds (wait: for the expression; others: to reach Chromium)")
    sub = parser.add_subparsers(dest="command", required=True)
    sub.add_parser("navigate").add_argument("url")
    sub.add_parser("eval").add_argument("expression")
    sub.add_parser("wait").add_argument("expression")
    sub.add_parser("screenshot").add_argument("path")
    args = parser.parse_args()
    try:
        page = Page(args.port)
        if args.command != "wait":
            page.ws.settimeout(args.timeout)
        if args.command == "navigate":
            page.call("Page.navigate", url=args.url)
        elif args.command == "eval":
            print(json.dumps(page.evaluate(args.expression)))
        elif args.command == "wait":
            deadline = time.monotonic() + args.timeout
            while True:
                try:
                    if page.evaluate(args.expression):
                        break
                except RuntimeError:
                    pass  # not defined yet (the page is loading)
                if time.monotonic() > deadline:
                    print(f"cdp.py: not true within {args.timeout} s: {args.expression}",
                          file=sys.stderr)
                    return 1
                time.sleep(0.25)
        elif args.command == "screenshot":
            data = page.call("Page.captureScreenshot", format="png")["data"]
            with open(args.path, "wb") as f:
                f.write(base64.b64decode(data))
        return 0
    except (RuntimeError, OSError, websocket.WebSocketException) as e:
        print(f"cdp.py: {e}", file=sys.stderr)
        return 1


if __name__ == "__main__":
    sys.exit(main())
