"""MkDocs hook: after the build, fail it when the site would load anything from the network.

The site must work opened from disk (``site/index.html``, no server, no network): ``mkdocs.yml`` turns
on Material's ``offline`` plugin (search from ``file://``) and ``theme.font: false`` (no Google Fonts).
This hook scans every built ``.html`` and ``.css`` file for a remote resource -- ``<script src>``,
``<link href>``, ``<img>``/``<iframe>``/``<source>``/``<video>``/``<audio>``/``<embed>`` ``src``,
``<object data>``, CSS ``@import`` and ``url(...)`` (in style sheets, ``<style>`` and ``style``
attributes) with a scheme or a protocol-relative ``//`` address -- and fails the build naming each
file and address. Plain links (``<a href>``) to other sites are navigation, not loads, and are allowed.
``tests/test_docs_offline.py`` tests the scanner and scans ``site/`` when a build is there.
"""

from __future__ import annotations

import re
from html.parser import HTMLParser
from pathlib import Path

#: an address that leaves the site: a scheme (http:, https:, ftp: ...) or protocol-relative //host
_REMOTE = re.compile(r"^\s*(?:[a-zA-Z][a-zA-Z0-9+.-]*:|//)")
#: schemes that load nothing from the network
_LOCAL_SCHEMES = ("data:", "blob:", "about:", "javascript:", "mailto:", "file:")
_CSS_URL = re.compile(r"""url\(\s*(['"]?)([^'")]*)\1\s*\)|@import\s+(['"])([^'"]+)\3""", re.I)
#: (tag, attribute) pairs whose value the browser loads
_LOADS = {
    ("script", "src"),
    ("link", "href"),
    ("img", "src"),
    ("img", "srcset"),
    ("iframe", "src"),
    ("source", "src"),
    ("source", "srcset"),
    ("video", "src"),
    ("video", "poster"),
    ("audio", "src"),
    ("embed", "src"),
    ("object", "data"),
    ("track", "src"),
    ("input", "src"),
}


def _remote(url: str) -> bool:
    return bool(_REMOTE.match(url)) and not url.strip().lower().startswith(_LOCAL_SCHEMES)


def css_remote_urls(css: str) -> list[str]:
    """The remote addresses a style sheet loads (``url(...)`` and ``@import``)."""
    return [u for m in _CSS_URL.finditer(css) if _remote(u := (m.group(2) or m.group(4) or ""))]


class _Scanner(HTMLParser):
    def __init__(self) -> None:
        super().__init__(convert_charrefs=True)
        self.found: list[str] = []
        self._in_style = False

    def handle_starttag(self, tag: str, attrs: list[tuple[str, str | None]]) -> None:
        for name, value in attrs:
            if value is None:
                continue
            if (tag, name) in _LOADS:
                urls = (
                    [u.split()[0] for u in value.split(",") if u.strip()]
                    if "srcset" in name
                    else [value]
                )
                self.found += [f"<{tag} {name}={u}>" for u in urls if _remote(u)]
            elif name == "style":
                self.found += [f"<{tag} style> url({u})" for u in css_remote_urls(value)]
        self._in_style = tag == "style"

    def handle_endtag(self, tag: str) -> None:
        self._in_style = False

    def handle_data(self, data: str) -> None:
        if self._in_style:
            self.found += [f"<style> url({u})" for u in css_remote_urls(data)]


def html_remote_loads(text: str) -> list[str]:
    """The remote resources an HTML page loads (see the module docstring); [] when none."""
    scanner = _Scanner()
    scanner.feed(text)
    scanner.close()
    return scanner.found


def remote_loads(site_dir: Path | str) -> list[str]:
    """``"FILE: what"`` for every remote load of the built site in ``site_dir``."""
    site = Path(site_dir)
    out = []
    for path in sorted(site.rglob("*")):
        if path.suffix == ".html":
            found = html_remote_loads(path.read_text(encoding="utf-8", errors="replace"))
        elif path.suffix == ".css":
            found = css_remote_urls(path.read_text(encoding="utf-8", errors="replace"))
        else:
            continue
        out += [f"{path.relative_to(site).as_posix()}: {f}" for f in found]
    return out


def on_post_build(config, **kwargs) -> None:
    from mkdocs.exceptions import PluginError

    found = remote_loads(config["site_dir"])
    if found:
        shown = "\n  ".join(found[:20]) + (
            f"\n  ... and {len(found) - 20} more" if len(found) > 20 else ""
        )
        raise PluginError(
            f"the built site loads {len(found)} remote resource(s); it must work offline "
            f"(docs/hooks/offline_check.py):\n  {shown}"
        )
