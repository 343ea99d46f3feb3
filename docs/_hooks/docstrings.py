"""MkDocs hook: read the package's docstrings as they are written.

* A unit in brackets after a bracketed term is not a cross-reference. The docstrings write units
  in brackets ("Rectangle [x_min, x_max] [m]", "F = (...)[1 - ...] [N]"); Markdown reads
  "[a] [m]" as a reference link to "m", and mkdocs-autorefs warns that no page defines it.
  Those warnings, and only those whose target is a unit, are dropped, so that
  ``mkdocs build --strict`` still fails on every other unresolved reference.
* Sphinx roles (":class:`X`", ":func:`~.mod.f`") are shown as the code they name; the
  docstrings use them, and the numpy-style parser leaves them in the text.
"""

from __future__ import annotations

import logging
import re

_UNIT = r"(?:N|m|s|Pa|kPa|rad|deg|kg|Hz|W|J|K|-|%|1)"
_UNIT_TARGET = re.compile(
    rf"Could not find cross-reference target '{_UNIT}(?:[ /·*^]?(?:{_UNIT}|\d))*'$")
_ROLE = re.compile(r":(?:class|mod|func|meth|attr|data|obj|exc|const):<code>~?\.?")


class _UnitReferences(logging.Filter):
    def filter(self, record: logging.LogRecord) -> bool:
        return not _UNIT_TARGET.search(record.getMessage())


def on_startup(command: str, dirty: bool) -> None:
    logging.getLogger("mkdocs.plugins.mkdocs_autorefs._internal.plugin").addFilter(
        _UnitReferences())


def on_page_content(html: str, page, config, files) -> str:
    return _ROLE.sub("<code>", html)
