"""XML helpers shared by the ``.ssd`` reader and writer (private to :mod:`orchestrator.ssp`).

Qualified tag names for the four namespaces, the prefix map the writer must use (libcosim's
parser matches element names with their prefix, not their namespace), element look-ups that
skip comments, and :class:`Problems`, which collects every problem of a file so that one
:class:`~components.common.errors.ConfigError` names all of them with file and line.
"""

from __future__ import annotations

from lxml import etree

from components.common.errors import ConfigError

from .model import OSP_NAMESPACE, SSC_NAMESPACE, SSD_NAMESPACE, SSV_NAMESPACE

__all__ = [
    "NSMAP",
    "ssd_tag",
    "ssc_tag",
    "ssv_tag",
    "osp_tag",
    "Problems",
    "describe",
    "required_attribute",
    "child_elements",
    "first_child",
    "float_attribute",
]

NSMAP = {"ssd": SSD_NAMESPACE, "ssc": SSC_NAMESPACE, "ssv": SSV_NAMESPACE, "osp": OSP_NAMESPACE}


def ssd_tag(tag):
    return f"{{{SSD_NAMESPACE}}}{tag}"


def ssc_tag(tag):
    return f"{{{SSC_NAMESPACE}}}{tag}"


def ssv_tag(tag):
    return f"{{{SSV_NAMESPACE}}}{tag}"


def osp_tag(tag):
    return f"{{{OSP_NAMESPACE}}}{tag}"


class Problems:
    """Collects parse problems so that one error names all of them."""

    def __init__(self, path):
        self.path = path
        self.lines = []

    def add(self, node, message):
        line = getattr(node, "sourceline", None)
        where = f"{self.path}:{line}" if line else f"{self.path}"
        self.lines.append(f"{where}: {message}")

    def raise_if_any(self):
        if len(self.lines) == 1:
            raise ConfigError(self.lines[0])
        if self.lines:
            count = len(self.lines)
            noun = "problem" if count == 1 else "problems"
            raise ConfigError(f"{self.path}: {count} {noun} in the system structure description:\n"
                              + "\n".join(f"  {line}" for line in self.lines))


def describe(node):
    qname = etree.QName(node)
    prefix = {v: k for k, v in NSMAP.items()}.get(qname.namespace, "?")
    name = node.get("name")
    return f"<{prefix}:{qname.localname}" + (f' name="{name}">' if name is not None else ">")


def required_attribute(node, attribute, problems):
    value = node.get(attribute)
    if value is None or value == "":
        problems.add(node, f"{describe(node)}: attribute '{attribute}' is missing")
    return value


def child_elements(node, tag):
    return [child for child in node if isinstance(child.tag, str) and child.tag == tag]


def first_child(node, tag):
    found = child_elements(node, tag)
    return found[0] if found else None


def float_attribute(node, attribute, problems):
    text = node.get(attribute)
    if text is None:
        return None
    try:
        return float(text)
    except ValueError:
        problems.add(node, f"{describe(node)}: {attribute}={text!r} is not a number")
        return None

