"""Open the built documentation site in a real headless browser.

Serves SITE on localhost, visits every page reachable from index.html
through internal links in Debian's Chromium (/usr/bin/chromium, driven by
playwright; no downloaded browser), and fails (exit 1) on:
  - an internal link to a page or file the server does not have (HTTP >= 400),
    or to an anchor the target page lacks;
  - an image that does not load (naturalWidth 0) or a failed request;
  - a JavaScript console error or an uncaught page error.
Screenshots the landing page and tutorial 1 into OUT and prints their paths.

    python docs/tools/browser_check.py SITE OUT
"""

import functools
import http.server
import os
import sys
import tempfile
import threading
import urllib.error
import urllib.parse
import urllib.request

from playwright.sync_api import sync_playwright

CHROMIUM = os.environ.get("CHROMIUM", "/usr/bin/chromium")
FLAGS = [
    "--headless", "--no-sandbox", "--disable-gpu", "--disable-quic", "--no-first-run",
    "--disable-background-networking", "--disable-component-update", "--disable-sync",
]
SHOTS = {"landing.png": "index.html", "tutorial-fig2.png": "tutorials/fig2.html"}


class Quiet(http.server.SimpleHTTPRequestHandler):
    def log_message(self, *args):
        pass


def serve(site):
    handler = functools.partial(Quiet, directory=site)
    server = http.server.ThreadingHTTPServer(("127.0.0.1", 0), handler)
    threading.Thread(target=server.serve_forever, daemon=True).start()
    return server, f"http://127.0.0.1:{server.server_address[1]}/"


def page_links(page, base):
    """(absolute URL without fragment, fragment) of every same-site link."""
    hrefs = page.eval_on_selector_all("a[href]", "els => els.map(e => e.href)")
    out = []
    for h in hrefs:
        url, frag = urllib.parse.urldefrag(h)
        if url.startswith(base):
            out.append((url, frag))
    return out


def status(url):
    """The HTTP status of a GET of `url`."""
    try:
        with urllib.request.urlopen(url) as r:
            return r.status
    except urllib.error.HTTPError as e:
        return e.code


def check_page(page, url, problems):
    """Load `url`; record console errors, failed requests and broken images."""
    errors = []
    page.on("console", lambda m: errors.append(f"console {m.type}: {m.text}") if m.type == "error" else None)
    page.on("pageerror", lambda e: errors.append(f"page error: {e}"))
    page.on("requestfailed", lambda r: errors.append(f"request failed: {r.url}"))
    page.on("response", lambda r: errors.append(f"HTTP {r.status}: {r.url}") if r.status >= 400 else None)
    resp = page.goto(url, wait_until="load")
    if resp is None or resp.status >= 400:
        problems.append(f"{url}: HTTP {resp.status if resp else 'no response'}")
        return False
    page.wait_for_timeout(100)
    broken = page.eval_on_selector_all(
        "img", "els => els.filter(e => !e.complete || e.naturalWidth === 0).map(e => e.src)")
    problems += [f"{url}: image does not load: {b}" for b in broken]
    problems += [f"{url}: {e}" for e in errors]
    return url.endswith(".html")


def main():
    site, out = os.path.abspath(sys.argv[1]), os.path.abspath(sys.argv[2])
    os.makedirs(out, exist_ok=True)
    server, base = serve(site)
    problems, seen, anchors_wanted, html = [], set(), [], {}
    with sync_playwright() as p, tempfile.TemporaryDirectory(ignore_cleanup_errors=True) as profile:
        browser = p.chromium.launch_persistent_context(
            profile, executable_path=CHROMIUM, args=FLAGS, headless=True,
            viewport={"width": 1280, "height": 900})
        queue = [base + "index.html"]
        while queue:
            url = queue.pop()
            if url in seen:
                continue
            seen.add(url)
            page = browser.new_page()
            if check_page(page, url, problems):
                html[url] = set(page.eval_on_selector_all("[id]", "els => els.map(e => e.id)"))
                for link, frag in page_links(page, base):
                    if link.endswith("/"):
                        link += "index.html"
                    if frag:
                        anchors_wanted.append((url, link, frag))
                    if link in seen:
                        continue
                    if link.endswith(".html"):
                        queue.append(link)
                    else:  # a file to download (a script, a notebook): the server must have it
                        seen.add(link)
                        if status(link) >= 400:
                            problems.append(f"{url}: link to a missing file {link}")
            page.close()
        for src, link, frag in anchors_wanted:
            if link in html and urllib.parse.unquote(frag) not in html[link]:
                problems.append(f"{src}: link to a missing anchor {link}#{frag}")
        for name, rel in SHOTS.items():
            page = browser.new_page()
            page.goto(base + rel, wait_until="load")
            page.screenshot(path=os.path.join(out, name), full_page=False)
            page.close()
        browser.close()
    server.shutdown()
    pages = sum(1 for u in seen if u.endswith(".html"))
    if problems:
        print(f"browser check: {len(problems)} problems over {pages} pages:")
        print("\n".join(sorted(set(problems))))
        sys.exit(1)
    print(f"browser check: {pages} pages, {len(seen) - pages} files, every link, image and script fine")
    for name in SHOTS:
        print(f"screenshot: {os.path.join(out, name)}")


if __name__ == "__main__":
    main()
