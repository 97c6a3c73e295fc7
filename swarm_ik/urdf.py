"""Reading URDF files robustly, before and around Pinocchio.

:func:`load_urdf` is what :meth:`swarm_ik.robot.RobotModel.from_urdf` calls to turn a file
into a full Pinocchio model:

1. :func:`read_urdf_text` decodes the file whatever its encoding (UTF-8 with or without a
   byte-order mark, UTF-16/32 with a BOM or an ``encoding=`` declaration) and drops
   whitespace before ``<?xml``; Pinocchio is given the normalised UTF-8 text.
2. :func:`check_urdf_xml` refuses what urdfdom would refuse with no useful message (an empty
   ``<robot>``, duplicate names, missing or non-finite limits, malformed origins and axes,
   loops) and reads the mimic joints (:class:`MimicJoint`).
3. :func:`rename_colliding_joints` renames, in an in-memory copy, every joint whose name is
   also a link name (``foot`` → ``foot_joint``): Pinocchio's frame look-ups (and
   ``buildReducedModel``) refuse such models with "Several frames match the filter".
   :attr:`UrdfInfo.renamed` maps the original names to the new ones and
   :meth:`UrdfInfo.joint_name` accepts either.
4. :func:`build_model` calls ``pinocchio.buildModelFromXML`` with the C-level ``stderr``
   (file descriptor 2) redirected, so urdfdom's own messages never reach the user; they are
   kept in :attr:`UrdfInfo.messages` and quoted in the error when the build fails.

:func:`default_ee_frame` chooses the end-effector frame when the user names none, the way a
person would (see its docstring); :func:`sampling_bounds` narrows huge joint ranges (the
±999999 "virtual" joints of mobile bases) to a window around the seed for random restarts.
"""

from __future__ import annotations

import codecs
import logging
import os
import re
import sys
import tempfile
import threading
import warnings
import xml.etree.ElementTree as ET
from collections import Counter
from collections.abc import Iterator
from contextlib import contextmanager
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
import pinocchio as pin

from swarm_ik._types import FloatArray
from swarm_ik._validate import one_line, user_stacklevel
from swarm_ik.errors import InvalidArgumentError, RobotModelError, RobotModelWarning

log = logging.getLogger("swarm_ik")

JOINT_TYPES = ("revolute", "continuous", "prismatic", "fixed", "floating", "planar")
"""Joint types of the URDF specification."""

DEFAULT_MAX_SAMPLING_WIDTH = 20.0
"""Widest joint range [rad or m] that random restarts sample uniformly (see
:func:`sampling_bounds`): wider than the revolute range of any real arm (UR's ±2π is
12.6 rad), and a room-sized window for the prismatic "virtual" joints of a mobile base."""


# --------------------------------------------------------------------------- reading
_BOMS = (
    (codecs.BOM_UTF32_LE, "utf-32-le"),
    (codecs.BOM_UTF32_BE, "utf-32-be"),
    (codecs.BOM_UTF8, "utf-8"),
    (codecs.BOM_UTF16_LE, "utf-16-le"),
    (codecs.BOM_UTF16_BE, "utf-16-be"),
)
_DECL = re.compile(r"^<\?xml[^>]*\?>", re.IGNORECASE)
_DECL_ENCODING = re.compile(rb"""^\s*<\?xml[^>]*encoding\s*=\s*["']([A-Za-z0-9._-]+)["']""")


def decode_xml_bytes(raw: bytes, where: str = "file") -> str:
    """Text of an XML document given as bytes, whatever its encoding.

    The encoding is taken from a byte-order mark, else from the pattern of zero bytes of a
    UTF-16/32 text without one, else from the ``encoding=`` of the XML declaration, else
    UTF-8.  Whitespace before the document and the XML declaration itself are removed (the
    text is Unicode now; Pinocchio gets it as UTF-8).

    Args:
        raw: The file's bytes.
        where: Name for messages (the path).

    Returns:
        The document text, starting at its first element, comment or processing
        instruction after the declaration.

    Raises:
        RobotModelError: the bytes cannot be decoded in the encoding they declare.
    """
    encoding = None
    for bom, name in _BOMS:
        if raw.startswith(bom):
            raw = raw[len(bom) :]
            encoding = name
            break
    if encoding is None and len(raw) >= 4:
        head = raw[:4]
        if head[0] == 0 and head[1] == 0 and head[2] == 0 and head[3] != 0:
            encoding = "utf-32-be"
        elif head[0] != 0 and head[1] == 0 and head[2] == 0 and head[3] == 0:
            encoding = "utf-32-le"
        elif head[0] == 0 and head[1] != 0:
            encoding = "utf-16-be"
        elif head[0] != 0 and head[1] == 0:
            encoding = "utf-16-le"
    if encoding is None:
        m = _DECL_ENCODING.match(raw)
        encoding = m.group(1).decode("ascii") if m else "utf-8"
    try:
        text = raw.decode(encoding)
    except LookupError:
        raise RobotModelError(
            f"{where}: unknown encoding {encoding!r} in the XML declaration"
        ) from None
    except UnicodeDecodeError as exc:
        raise RobotModelError(
            f"{where}: not valid {encoding} text ({exc.reason} at byte {exc.start})"
        ) from None
    text = text.lstrip("\ufeff \t\r\n")
    return _DECL.sub("", text, count=1).lstrip()


def read_urdf_text(path: str | os.PathLike[str]) -> str:
    """The text of a URDF file, decoded and normalised by :func:`decode_xml_bytes`.

    Raises:
        RobotModelError: unreadable or undecodable file.
    """
    p = Path(path)
    try:
        raw = p.read_bytes()
    except OSError as exc:
        raise RobotModelError(f"{p}: cannot read the file ({exc.strerror or exc})") from None
    return decode_xml_bytes(raw, str(p))


# --------------------------------------------------------------------------- checking
@dataclass(frozen=True)
class MimicJoint:
    """A URDF ``<mimic>``: ``q[name] = multiplier · q[driver] + offset``.

    Attributes:
        name: The following joint (its name in the Pinocchio model, after renaming).
        driver: The joint it follows (name in the Pinocchio model).
        multiplier: ``a`` of ``a·q + b`` (URDF default 1).
        offset: ``b`` of ``a·q + b`` [rad or m] (URDF default 0).
    """

    name: str
    driver: str
    multiplier: float = 1.0
    offset: float = 0.0

    def follower_value(self, q_driver: Any) -> Any:
        """The follower's value(s) for driver value(s) ``q_driver`` (same shape)."""
        return self.multiplier * np.asarray(q_driver, dtype=float) + self.offset


def _xyz(where: str, joint: str | None, el: ET.Element | None, attr: str) -> FloatArray | None:
    """The 3 numbers of attribute ``attr`` of ``el`` (``None`` when absent); refuses
    malformed or non-finite values, naming the joint."""
    if el is None:
        return None
    raw = el.get(attr)
    if raw is None:
        return None
    try:
        vals = np.array([float(v) for v in raw.split()])
    except ValueError:
        vals = np.array([])
    if vals.shape != (3,) or not np.all(np.isfinite(vals)):
        raise RobotModelError(
            f"{where}: joint {joint!r}: <{el.tag} {attr}={raw!r}> must be 3 finite numbers"
        )
    return vals


def _mimic_of(where: str, name: str, el: ET.Element) -> MimicJoint:
    vals = []
    for attr, default in (("multiplier", 1.0), ("offset", 0.0)):
        raw = el.get(attr)
        try:
            v = default if raw is None else float(raw)
        except ValueError:
            v = float("nan")
        if not np.isfinite(v):
            raise RobotModelError(
                f"{where}: joint {name!r}: <mimic {attr}={raw!r}> must be a finite number"
            )
        vals.append(v)
    if vals[0] == 0.0:
        raise RobotModelError(
            f"{where}: joint {name!r}: <mimic multiplier=0> would hold it still at its offset "
            "whatever its driver does; make it a fixed joint (or give a non-zero multiplier)"
        )
    return MimicJoint(name, str(el.get("joint")), vals[0], vals[1])


def parse_urdf_xml(text: str, where: str = "URDF") -> ET.Element:
    """The ``<robot>`` element of a URDF text.

    Raises:
        RobotModelError: not XML, or the root element is not ``<robot>``.
    """
    try:
        root = ET.fromstring(text)
    except ET.ParseError as exc:
        raise RobotModelError(f"{where}: not a valid XML file ({exc})") from None
    if root.tag != "robot":
        raise RobotModelError(
            f"{where}: not a URDF (root element is <{root.tag}>, expected <robot>)"
        )
    macro = next((el for el in root.iter() if str(el.tag).startswith(XACRO_TAG)), None)
    expression = any("${" in v for el in root.iter() for v in el.attrib.values())
    if macro is not None or expression:  # (urdfdom skips the unknown elements: the macros'
        # links and joints were left out in silence)
        what = f"<xacro:{str(macro.tag)[len(XACRO_TAG) :]}>" if macro is not None else "${...}"
        raise RobotModelError(
            f"{where}: a xacro file ({what}): xacro files must be expanded first: run "
            "`xacro FILE > robot.urdf` (ROS's xacro package) and load robot.urdf"
        )
    return root


XACRO_TAG = "{http://www.ros.org/wiki/xacro}"
"""The namespace of xacro's elements (``xmlns:xacro="http://www.ros.org/wiki/xacro"``), as
ElementTree names them."""


MAX_LINKS = 10_000
"""Most links of a URDF read (a humanoid has about 100)."""
MAX_DEPTH = 1000
"""Most links on one root-to-leaf chain (Pinocchio's recursive URDF parser crashes the
process on chains of a few thousand)."""


def check_urdf_xml(root: ET.Element, where: str = "URDF") -> dict[str, MimicJoint]:
    """Refuse what urdfdom would refuse with no useful message: an empty ``<robot>``,
    duplicate names, missing or non-finite limits, malformed origins and axes, loops.

    Args:
        root: The ``<robot>`` element (:func:`parse_urdf_xml`).
        where: Name for messages (the path).

    Returns:
        The mimic joints: follower name (as in the file) -> :class:`MimicJoint`.

    Raises:
        RobotModelError: the first problem found, naming the joint or link.
    """
    link_list = [link.get("name") for link in root.findall("link")]
    joint_list = [joint.get("name") for joint in root.findall("joint")]
    if not link_list:
        name = root.get("name")
        label = f"<robot name={name!r}>" if name else "<robot>"
        raise RobotModelError(
            f"{where}: the URDF is empty: {label} defines no <link>"
            + (f" (and {len(joint_list)} joint(s))" if joint_list else "")
        )
    if len(link_list) > MAX_LINKS:
        raise RobotModelError(
            f"{where}: {len(link_list)} links; at most {MAX_LINKS} are read (swarm_ik.urdf."
            "MAX_LINKS: Pinocchio's loading time grows faster than the link count)"
        )
    links = set(link_list)
    for label, names in (("link", link_list), ("joint", joint_list)):
        counts = Counter(names)
        dup = sorted({str(n) for n, k in counts.items() if k > 1})
        if dup:
            raise RobotModelError(f"{where}: {label} name(s) {dup} defined more than once")
    children: set[str] = set()
    mimic: dict[str, MimicJoint] = {}
    for joint in root.findall("joint"):
        name = joint.get("name")
        jtype = joint.get("type")
        if jtype not in JOINT_TYPES:
            raise RobotModelError(
                f"{where}: joint {name!r} has unknown type {jtype!r}; valid types: "
                + ", ".join(JOINT_TYPES)
            )
        parent = joint.find("parent")
        child = joint.find("child")
        for tag, el in (("parent", parent), ("child", child)):
            link = None if el is None else el.get("link")
            if link not in links:
                raise RobotModelError(
                    f"{where}: joint {name!r} names {tag} link {link!r}, which is not defined"
                )
        assert child is not None
        c = child.get("link")
        if c in children:
            raise RobotModelError(
                f"{where}: link {c!r} is the child of two joints (a kinematic loop)"
            )
        children.add(str(c))
        origin = joint.find("origin")
        _xyz(where, name, origin, "xyz")
        _xyz(where, name, origin, "rpy")
        axis = _xyz(where, name, joint.find("axis"), "xyz")
        if axis is not None and jtype not in ("fixed", "floating") and np.linalg.norm(axis) < 1e-9:
            raise RobotModelError(f"{where}: joint {name!r} has a zero axis {axis.tolist()}")
        el_mimic = joint.find("mimic")
        if el_mimic is not None:
            mimic[str(name)] = _mimic_of(where, str(name), el_mimic)
        limit = joint.find("limit")
        if jtype in ("revolute", "prismatic"):
            if limit is None:
                raise RobotModelError(
                    f"{where}: {jtype} joint {name!r} has no <limit lower=... upper=...>; "
                    "URDF requires limits on revolute and prismatic joints (use type "
                    "'continuous' for a revolute joint without limits)"
                )
            if limit.get("lower") is None and limit.get("upper") is None:
                warnings.warn(
                    f"{where}: {jtype} joint {name!r} has a <limit> without lower and upper: "
                    "URDF's default [0, 0] holds it still (give lower=... upper=..., or make "
                    "it a fixed joint)",
                    RobotModelWarning,
                    stacklevel=user_stacklevel(),
                )
            try:
                lo = float(limit.get("lower", "0"))
                hi = float(limit.get("upper", "0"))
            except ValueError:
                raise RobotModelError(
                    f"{where}: joint {name!r} has non-numeric limits "
                    f"[{limit.get('lower')!r}, {limit.get('upper')!r}]"
                ) from None
            if not (np.isfinite(lo) and np.isfinite(hi)):
                raise RobotModelError(f"{where}: joint {name!r} has non-finite limits [{lo}, {hi}]")
            if lo > hi:
                raise RobotModelError(
                    f"{where}: joint {name!r} has lower limit {lo} > upper limit {hi}"
                )
    # a dangling reference: the follower moves on its own, as Pinocchio loads it, with one
    # warning (example-robot-data's alex_psyonic_hands names 8 drivers it does not have)
    dangling = {f: m.driver for f, m in mimic.items() if m.driver not in joint_list}
    if dangling:
        for follower in dangling:
            del mimic[follower]
        pairs = ", ".join(f"{f!r} → {d!r}" for f, d in dangling.items())
        warnings.warn(
            f"{where}: {len(dangling)} joint(s) mimic a joint that is not in the file "
            f"({pairs}); they are loaded as independent joints",
            RobotModelWarning,
            stacklevel=user_stacklevel(),
        )
    roots = links - children
    if len(roots) != 1:
        raise RobotModelError(
            f"{where}: a URDF needs exactly one root link, found "
            f"{sorted(map(str, roots)) or 'none'} (a loop or a disconnected link)"
        )
    parent_of = {}
    for joint in root.findall("joint"):
        p_el, c_el = joint.find("parent"), joint.find("child")
        assert p_el is not None and c_el is not None  # (checked above)
        parent_of[str(c_el.get("link"))] = str(p_el.get("link"))
    depth: dict[str, int] = {str(next(iter(roots))): 0}
    for link in map(str, links):  # depth of every link, each walked once
        path = []
        while link not in depth:
            path.append(link)
            link = parent_of[link]
        d = depth[link]
        for up in reversed(path):
            d += 1
            depth[up] = d
        if d > MAX_DEPTH:
            raise RobotModelError(
                f"{where}: a chain of {d} links from the root; at most {MAX_DEPTH} are read "
                "(swarm_ik.urdf.MAX_DEPTH: deeper trees overflow the stack of the URDF parser)"
            )
    return mimic


def rename_colliding_joints(root: ET.Element) -> dict[str, str]:
    """Rename, in place, every joint whose name is also a link name.

    The new name is ``<name>_joint`` (``<name>_joint2``, ``_joint3``… when that is taken).
    ``<mimic joint=…>`` and ``<transmission>`` references are renamed with it.

    Args:
        root: The ``<robot>`` element; modified in place.

    Returns:
        Original joint name -> new name (empty when nothing collided).
    """
    links = {str(link.get("name")) for link in root.findall("link")}
    joints = root.findall("joint")
    taken = links | {str(j.get("name")) for j in joints}
    renamed: dict[str, str] = {}
    for joint in joints:
        name = str(joint.get("name"))
        if name not in links:
            continue
        new, k = f"{name}_joint", 1
        while new in taken:
            k += 1
            new = f"{name}_joint{k}"
        taken.add(new)
        renamed[name] = new
        joint.set("name", new)
    if renamed:
        for el in root.iter("mimic"):
            ref = el.get("joint")
            if ref in renamed:
                el.set("joint", renamed[ref])
        for tr in root.iter("transmission"):
            for el in tr.iter("joint"):
                ref = el.get("name")
                if ref in renamed:
                    el.set("name", renamed[ref])
    return renamed


# --------------------------------------------------------------------------- building
_FD_LOCK = threading.Lock()


@contextmanager
def captured_stderr() -> Iterator[list[str]]:
    """Redirect the process's file descriptor 2 (where C and C++ libraries such as urdfdom
    write) to a temporary file; the yielded list receives the captured lines on exit.

    Falls back to no capture when descriptor 2 cannot be duplicated.  A lock serialises
    concurrent uses (descriptor 2 belongs to the whole process).
    """
    lines: list[str] = []
    with _FD_LOCK:
        try:
            sys.stderr.flush()
        except (AttributeError, ValueError, OSError):
            pass
        try:
            saved = os.dup(2)
        except OSError:
            yield lines
            return
        with tempfile.TemporaryFile() as tmp:
            os.dup2(tmp.fileno(), 2)
            try:
                yield lines
            finally:
                try:
                    sys.stderr.flush()
                except (AttributeError, ValueError, OSError):
                    pass
                os.dup2(saved, 2)
                os.close(saved)
                tmp.seek(0)
                text = tmp.read().decode("utf-8", errors="replace")
                lines.extend(line.strip() for line in text.splitlines() if line.strip())


def build_model(
    xml: str, where: str = "URDF", floating_base: bool = False
) -> tuple[Any, tuple[str, ...]]:
    """``pinocchio.buildModelFromXML(xml)`` with urdfdom's stderr captured.

    Args:
        xml: URDF text.
        where: Name for messages (the path).
        floating_base: Root the model on a free flyer (``pinocchio.JointModelFreeFlyer()``,
            named ``root_joint``).

    Returns:
        ``(model, messages)``: the full Pinocchio model (mimic joints as independent joints)
        and what urdfdom printed.

    Raises:
        RobotModelError: Pinocchio or urdfdom refused the text (their message quoted).
    """
    error: str | None = None
    model = None
    with captured_stderr() as lines:
        try:
            if floating_base:
                model = pin.buildModelFromXML(xml, pin.JointModelFreeFlyer())
            else:
                model = pin.buildModelFromXML(xml)
        except Exception as exc:  # Pinocchio raises plain ValueError/RuntimeError
            error = str(exc).strip() or type(exc).__name__
    messages = tuple(lines)
    if error is not None or model is None:
        said = _complaints(messages)  # (urdfdom's first complaint is the cause)
        detail = "; ".join([*said[:1], error or ""]).strip("; ")
        raise RobotModelError(f"{where}: Pinocchio could not load it ({one_line(detail, 300)})")
    for line in messages:
        log.debug("%s: urdfdom: %s", where, line)
    _warn_of_skipped_inertials(where, messages)
    return model, messages


def _complaints(messages: tuple[str, ...]) -> list[str]:
    """urdfdom's messages without their ``Error:`` prefix and their ``at line N in file.cpp``
    lines."""
    return [re.sub(r"^Error:\s*", "", m).strip() for m in messages if not m.startswith("at line")]


def _warn_of_skipped_inertials(where: str, messages: tuple[str, ...]) -> None:
    """A warning per link whose ``<inertial>`` urdfdom could not read (``mass [abc] is not a
    float``): it loads the link with no mass, so a centre of mass would be wrong where plain
    IK is not (a warning, not a refusal; urdfdom's messages are otherwise kept at DEBUG)."""
    said = _complaints(messages)
    for k, line in enumerate(said):
        link = re.match(r"Could not parse inertial element for Link \[(.*)\]$", line)
        if link is None:
            continue
        cause = f" ({said[k - 1]})" if k > 0 and not said[k - 1].startswith("Could not") else ""
        warnings.warn(
            f"{where}: the inertial of link {link.group(1)!r} could not be read{cause}; the link "
            "is loaded without mass (a CenterOfMass goal would be wrong)",
            RobotModelWarning,
            stacklevel=user_stacklevel(),
        )


@dataclass(frozen=True)
class UrdfInfo:
    """What :func:`load_urdf` learnt about a file beyond the Pinocchio model.

    Attributes:
        path: The file.
        xml: The text given to Pinocchio (normalised, joints renamed).
        mimic: Mimic joints: follower name in the model -> :class:`MimicJoint` (names in
            the model, i.e. after renaming).
        renamed: Original joint name -> name in the model, for the joints renamed because a
            link has the same name.
        child_link: Joint name in the model -> its child link.
        messages: What urdfdom printed while parsing (captured, not shown).
    """

    path: Path
    xml: str
    mimic: dict[str, MimicJoint] = field(default_factory=dict)
    renamed: dict[str, str] = field(default_factory=dict)
    child_link: dict[str, str] = field(default_factory=dict)
    messages: tuple[str, ...] = ()

    def joint_name(self, name: str) -> str:
        """The model's name of joint ``name`` (an original URDF name or a model name)."""
        return self.renamed.get(name, name)

    @property
    def mimic_drivers(self) -> dict[str, str]:
        """Follower -> driver (model names), the form the chain-building code refuses."""
        return {k: m.driver for k, m in self.mimic.items()}


def load_urdf(path: str | os.PathLike[str], floating_base: bool = False) -> tuple[Any, UrdfInfo]:
    """Read, check, repair (in memory) and build a URDF file.

    Args:
        path: The URDF file (must exist).
        floating_base: Root the model on a free flyer (see :func:`build_model`).

    Returns:
        ``(full Pinocchio model, UrdfInfo)``.

    Raises:
        RobotModelError: not a usable URDF; the message starts with the path and names the
            problem (one line).
    """
    p = Path(path)
    where = str(p)
    text = read_urdf_text(p)
    root = parse_urdf_xml(text, where)
    mimic = check_urdf_xml(root, where)
    renamed = rename_colliding_joints(root)
    xml = ET.tostring(root, encoding="unicode") if renamed else text
    mimic_model = {
        renamed.get(k, k): MimicJoint(
            renamed.get(k, k), renamed.get(m.driver, m.driver), m.multiplier, m.offset
        )
        for k, m in mimic.items()
    }
    child_link = {}
    for joint in root.findall("joint"):
        child = joint.find("child")
        if child is not None:
            child_link[str(joint.get("name"))] = str(child.get("link"))
    model, messages = build_model(xml, where, floating_base)
    return model, UrdfInfo(p, xml, mimic_model, renamed, child_link, messages)


# --------------------------------------------------------------------------- default frame
FINGER_WORDS = ("finger", "thumb", "knuckle", "jaw", "claw", "gripper", "phalan", "pinch")
"""A movable joint whose name has a word containing one of these, or whose child link's name
has a word containing one of them other than ``gripper`` (a link named ``gripper`` is
usually the gripper's body, moved by the wrist), is a gripper joint for
:func:`default_ee_frame`."""

FINGER_NAMES = ("hand", "index", "middle", "ring", "little", "pinky", "mrl", "palm")
"""Whole words that mark a movable joint's *name* as a hand joint (``hand_index_flex_1``)."""

FRAME_NAME_SCORES = (
    (("camera", "range", "imu", "sensor", "laser", "accelerometer", "ft", "finger"), -1),
    (("tcp",), 6),
    (("tool",), 5),
    (("ee", "eef", "endeffector", "end_effector", "effector"), 4),
    (("flange",), 3),
    (("hand", "gripper", "wrist"), 2),
)
"""Frame-name preference of :func:`default_ee_frame`: the score of the first group one of
whose words is a word of the name (digits stripped: ``tool0`` → ``tool``; words of five
letters or more also match inside a word: ``fingertip``, ``endeffector``); sensor and finger
frames first, so ``left_hand_camera`` scores -1."""


def name_words(name: str) -> list[str]:
    """Lower-case words of a frame or joint name, split at non-letters and camelCase
    (``"panda_hand_tcp"`` → ``panda, hand, tcp``; ``"gripperMover"`` → ``gripper, mover``;
    ``"tool0"`` → ``tool``)."""
    parts = re.split(r"[^A-Za-z0-9]+|(?<=[a-z])(?=[A-Z])", name)
    words = [re.sub(r"\d+", "", w).lower() for w in parts]
    return [w for w in words if w]


def frame_name_score(name: str) -> int:
    """Preference of a frame name (:data:`FRAME_NAME_SCORES`; 0 when no word matches)."""
    words = name_words(name)
    joined = "_".join(words)
    for group, score in FRAME_NAME_SCORES:
        for g in group:
            if "_" in g and g in joined:
                return score
            if any(w == g or (len(g) >= 5 and g in w) for w in words):
                return score
    return 0


def is_gripper_joint(name: str, child_link: str | None = None) -> bool:
    """Whether a movable joint drives a gripper finger, judged by its name and its child
    link's (:data:`FINGER_WORDS`)."""
    words = name_words(name)
    if any(f in w for w in words for f in FINGER_WORDS) or any(w in FINGER_NAMES for w in words):
        return True
    link_words = name_words(child_link) if child_link else []
    return any(f in w for w in link_words for f in FINGER_WORDS if f != "gripper")


def default_ee_frame(model: Any, info: UrdfInfo | None = None) -> tuple[str, str]:
    """The end-effector frame a person would pick, and why.

    Rule: among the links (BODY frames), keep those whose chain from the root holds only
    one-DoF joints, no gripper joint and no mimic joint the model cannot drive; pick the one
    with the most solved joints on its chain (mimic followers, driven by their drivers, do not
    count); among those, the best name (:func:`frame_name_score`: tcp > tool >
    ee/eef/end_effector > flange > hand/gripper/wrist > others > camera/sensor/ft/finger), then
    the one furthest along fixed joints from the last movable joint (the tip), then the first
    in the file.  When no link qualifies (a hand alone, a free-floating body), the rule falls
    back to the link on the deepest joint.

    A gripper joint is a joint named like a finger (:func:`is_gripper_joint`), or a joint of
    a mimic group (a driver and its followers) that carries no other arm joint: no movable
    joint below it that is neither in a mimic group nor named like a finger (a gripper's
    fingers, whatever their names).  A mimic joint inside an arm (a parallelogram's joint
    driven by the shoulder, with the wrist beyond it) is an arm joint: it does not cut the
    chain.  A chain is refused where :meth:`swarm_ik.robot.RobotModel.from_urdf` would refuse
    it: a follower whose driver is not on the chain, a follower of a follower, a missing
    driver, or a continuous or multi-DoF joint in a mimic group.

    Args:
        model: Full Pinocchio model.
        info: The file's :class:`UrdfInfo` (mimic joints, child links); ``None``: judged by
            joint names only.

    Returns:
        ``(frame name, reason)``; the reason is one sentence for logs and listings.
    """
    frames = list(model.frames)
    mimic = info.mimic if info is not None else {}
    child_link = info.child_link if info is not None else {}
    names = list(model.names)
    jid = {n: j for j, n in enumerate(names) if j > 0}
    group = {m.driver: m.driver for m in mimic.values()}  # joint -> its group's driver
    group.update({f: m.driver for f, m in mimic.items()})
    finger = [
        j > 0 and is_gripper_joint(names[j], child_link.get(names[j])) for j in range(len(names))
    ]
    unsupported = set()  # groups refused: a missing or mimic driver, a continuous joint
    for f, m in mimic.items():
        members = [n for n in (f, m.driver) if n in jid]
        if (
            m.driver not in jid
            or m.driver in mimic
            or any(model.joints[jid[n]].nq != 1 for n in members)
        ):
            unsupported.add(m.driver)
            if m.driver in mimic:  # (a follower of a follower: its driver's group too)
                unsupported.add(mimic[m.driver].driver)
    # a free flyer at the root (load_robot(..., floating_base=True)) is on every chain: the
    # rule reads the chains below it as it does without it
    flyer = [
        j > 0 and model.parents[j] == 0 and model.joints[j].shortname() == "JointModelFreeFlyer"
        for j in range(model.njoints)
    ]
    bad_joint = [False] * model.njoints
    refused = [False] * model.njoints  # (an arm joint of a mimic group the model refuses)
    for j in range(1, model.njoints):
        jname = names[j]
        if flyer[j]:
            continue
        bad_joint[j] = model.joints[j].nv != 1 or finger[j]
        if jname in group and not bad_joint[j]:
            carries_arm = any(
                model.joints[k].nv >= 1 and names[k] not in group and not finger[k]
                for k in model.subtrees[j]
                if k != j
            )  # (a mimic group moving only itself and fingers: a gripper)
            bad_joint[j] = group[jname] in unsupported or not carries_arm
            refused[j] = carries_arm and group[jname] in unsupported

    def drivable(chain: list[int]) -> bool:
        """Whether every mimic follower on ``chain`` has its driver on it too."""
        on = {names[j] for j in chain}
        return all(mimic[n].driver in on for n in on if n in mimic)

    def fixed_depth(i: int) -> int:
        d = 0
        while frames[i].type != pin.FrameType.JOINT and i > 0 and d < len(frames):
            i = int(frames[i].parentFrame)
            d += 1
        return d

    best: tuple[Any, ...] | None = None
    best_i = -1
    cut = (0, "", "")  # the longest chain cut by a refused mimic group: (joints, frame, joint)
    for i, f in enumerate(frames):
        if f.type != pin.FrameType.BODY:
            continue
        chain = [int(j) for j in model.supports[f.parentJoint] if j != 0 and not flyer[j]]
        if chain and all(refused[j] or not bad_joint[j] for j in chain):
            first = next((j for j in chain if refused[j]), None)
            if first is not None and len(chain) > cut[0]:
                cut = (len(chain), f.name, names[first])
        if not chain or any(bad_joint[j] for j in chain) or not drivable(chain):
            continue
        solved = sum(names[j] not in mimic for j in chain)
        key = (solved, frame_name_score(f.name), fixed_depth(i), -i)
        if best is None or key > best:
            best, best_i = key, i
    if best is not None and cut[0] > best[0]:  # (an arm of refused mimic joints: the frame
        # before them was taken in silence, a 6-joint arm solved as 2 joints)
        warnings.warn(
            f"the default end-effector frame stops before joint {cut[2]!r}: a longer chain "
            f"(to {cut[1]!r}, {cut[0]} joints) holds mimic joints swarm_ik cannot drive; name "
            "the frame to be told why",
            RobotModelWarning,
            stacklevel=user_stacklevel(),
        )
    if best is not None:
        f = frames[best_i]
        n = best[0]
        chain = [int(j) for j in model.supports[f.parentJoint] if j != 0 and not flyer[j]]
        k = len(chain) - n
        driven = f" and {k} mimic joint{'s' if k != 1 else ''} they drive" if k else ""
        why = (
            f"default end-effector frame {f.name!r}: tip of the longest movable chain "
            f"({n} joint{'s' if n != 1 else ''}{driven}, {model.names[chain[0]]} … "
            f"{model.names[chain[-1]]}) without gripper joints"
        )
        if best[1] > 0:
            why += ", preferred for its name"
        return f.name, why
    depth = [len(model.supports[f.parentJoint]) for f in frames]
    cand = [i for i, f in enumerate(frames) if f.type == pin.FrameType.BODY]
    i = max(cand, key=lambda i: (depth[i], i))
    return frames[i].name, (
        f"default end-effector frame {frames[i].name!r}: the link on the deepest joint (no "
        "chain without gripper, unsupported mimic or multi-DoF joints)"
    )


# --------------------------------------------------------------------------- sampling
def sampling_bounds(
    lower: Any,
    upper: Any,
    seed_q: Any = None,
    max_width: float = DEFAULT_MAX_SAMPLING_WIDTH,
) -> tuple[FloatArray, FloatArray]:
    """Bounds for random restarts: joint ranges wider than ``max_width`` narrowed to a
    window of width ``max_width`` around the seed.

    Rule: a joint whose range ``upper − lower`` is at most ``max_width`` keeps it; a wider
    one (e.g. a mobile base's "virtual" joint limited to ±999999 m) samples
    ``[s − w/2, s + w/2]`` with ``s`` its seed value and ``w = max_width``, shifted to lie
    inside ``[lower, upper]`` (so the window keeps its width).  Uniform restarts over a
    million metres would practically never land near the target; the window is centred
    on the seed, which the caller can set to where the base is.

    Args:
        lower: Lower limits, shape ``(nq,)`` [rad or m].
        upper: Upper limits, shape ``(nq,)``.
        seed_q: Seed, shape ``(nq,)`` (clipped into the limits); ``None``: the middle of the
            ranges.
        max_width: Widest range sampled as is [rad or m], finite and positive (default
            :data:`DEFAULT_MAX_SAMPLING_WIDTH`).

    Returns:
        ``(lo, hi)``, shape ``(nq,)`` each, with ``lower <= lo <= hi <= upper``.

    Raises:
        InvalidArgumentError: shapes differ, non-finite values, ``lower > upper``, or a bad
            ``max_width``.
    """
    lo = np.asarray(lower, dtype=float)
    hi = np.asarray(upper, dtype=float)
    if lo.ndim != 1 or lo.shape != hi.shape:
        raise InvalidArgumentError(
            f"lower and upper must be 1-D of the same length, got shapes {lo.shape}, {hi.shape}"
        )
    if not (np.all(np.isfinite(lo)) and np.all(np.isfinite(hi))) or np.any(lo > hi):
        raise InvalidArgumentError("lower and upper must be finite with lower <= upper")
    try:
        w = float(max_width)
    except (TypeError, ValueError):
        w = float("nan")
    if isinstance(max_width, bool) or not (0.0 < w < np.inf):
        raise InvalidArgumentError(f"max_width must be a positive finite number, got {max_width!r}")
    if seed_q is None:
        s = 0.5 * (lo + hi)
    else:
        s = np.asarray(seed_q, dtype=float)
        if s.shape != lo.shape or not np.all(np.isfinite(s)):
            raise InvalidArgumentError(
                f"seed_q must be {lo.shape[0]} finite numbers, got {np.asarray(seed_q).tolist()}"
            )
        s = np.clip(s, lo, hi)
    wide = (hi - lo) > w
    out_lo, out_hi = lo.copy(), hi.copy()
    if wide.any():
        a = np.clip(s[wide] - 0.5 * w, lo[wide], hi[wide] - w)
        out_lo[wide] = a
        out_hi[wide] = a + w
    return out_lo, out_hi
