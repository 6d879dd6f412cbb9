"""Li, Liu, He, Liu, Liu (IEEE Access 2020): distributed adaptive FTC for spacecraft formation with
communication delays. Its scenarios are composed (controller ``li2020-adaptive`` / ``sir-ftc``); this
package registers reproduction ``li2020``, the theorems' conditions and the figures (errata E000-* in
docs/errata.md).
"""

from formation_ftc.papers.li2020 import registration  # noqa: F401
