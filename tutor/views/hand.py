"""Who moves the arm in Experiment 2: the trainee's own hand, or the tutor's guided hand.

Two *hands* give a demonstration (:data:`HANDS`):

``own`` (the default, :data:`DEFAULT_HAND`)
    The trainee guides the arm themself in the 3-D view: a ball on the gripper dragged
    with the mouse, the arrow keys, a gamepad (:mod:`tutor.views.scene_guide`).
``guided``
    The tutor guides the arm for them: they click a plant, may choose a mistake, and
    press Demonstrate (:mod:`tutor.tasks.kinesthetic`). For simulated teachers, for
    trainees who cannot use a mouse or keyboard, and wherever an educator chooses it.

Which hand a run uses (:func:`choose_hand`): the one asked for explicitly, else the
class plan's ``hand`` column (:mod:`tutor.framework.assignment`), else the environment
variable :data:`HAND_ENV` (``TUTOR_HAND``) of the notebook server, else the default.

Everything that differs between the hands is a field of its :class:`Hand` (the words,
whether the "mistake" menu is offered, the controls); nothing elsewhere tests a hand's
name. :func:`controls_html` writes a hand's controls as an accessible HTML list of keys
(``<dl>`` with ``<kbd>``), the one the practice run and the worked example show.
"""

from __future__ import annotations

import html
from dataclasses import dataclass

from ..errors import InvalidParameterError
from ..runtime import env_text
from .style import PROSE

__all__ = [
    "Hand",
    "HANDS",
    "HAND_TASKS",
    "HAND_ENV",
    "DEFAULT_HAND",
    "check_hand",
    "choose_hand",
    "hand_and_source",
    "HAND_SOURCES",
    "controls_html",
    "hand_from_env",
]

#: the environment variable an educator sets to choose the hand for a whole server
HAND_ENV = "TUTOR_HAND"
#: the hand when nobody chooses one: the trainee guides the arm themself
DEFAULT_HAND = "own"


@dataclass(frozen=True)
class Hand:
    """One way of giving a demonstration.

    Attributes
    ----------
    code : str
        Its name in plans, the environment and run records ("own", "guided").
    label : str
        What the trainee reads, e.g. "Guide the arm yourself".
    words : str
        What the trainee does, in a sentence or two; shown after the label (so it does
        not say the label again).
    trainee_moves : bool
        The trainee moves the arm in the 3-D view (the own hand); otherwise the tutor
        moves it to the plant the trainee clicked (the guided hand).
    mistake_menu : bool
        Whether the "mistake" menu (wrong plant, sloppy grab) is offered: only the
        guided hand makes mistakes on request; an own hand makes its own.
    controls : tuple of (str, tuple of str, str)
        The controls, each a gesture in words ("" for none), the keys that do the same
        (none for a gesture alone), and what they do.
    try_it : str
        The "Try the controls" step before the first demonstration (the paper's
        familiarisation), in a few sentences.
    """

    code: str
    label: str
    words: str
    trainee_moves: bool
    mistake_menu: bool
    controls: tuple[tuple[str, tuple[str, ...], str], ...]
    try_it: str

    @property
    def how(self) -> str:
        """The controls as one line of text, e.g. "drag the ball on the gripper: ..."."""
        return "; ".join(f"{_said(g, k)}: {what}" for g, k, what in self.controls) + "."


def _said(gesture: str, keys, kbd=lambda key: key) -> str:
    """A control's gesture and keys in words, e.g. "Shift + drag the ball, or E or Q"."""
    keys = " or ".join(kbd(k) for k in keys)
    return ", or ".join(part for part in (gesture, keys) if part)


#: the hands, by code (the first is the default)
#: the tasks taught with a hand on the arm (the maze is drawn with the pointer)
HAND_TASKS = ("pickplace",)

HANDS = {
    "own": Hand(
        code="own",
        label="Guide the arm yourself",
        words=(
            "Select a plant, press Guide the arm, move the gripper to the plant, close the "
            "hand on it, carry it to the bin, open the hand and press Enter."
        ),
        trainee_moves=True,
        mistake_menu=False,
        controls=(
            ("drag the ball on the gripper", (), "move the hand across the table"),
            ("Shift + drag the ball", ("E", "Q"), "move the hand up (E) or down (Q)"),
            ("", ("←", "→", "↑", "↓"), "move the hand across the table, a step a press"),
            ("", ("Space",), "close or open the hand"),
            ("", ("Enter",), "end the demonstration (the robot then learns from it)"),
            ("", ("Escape",), "cancel the demonstration (nothing is kept)"),
            ("a gamepad's sticks", (), "move the hand; its button A closes or opens it"),
        ),
        try_it=(
            "Before your first demonstration, take about 5 minutes to try the controls, as "
            "the paper's trainees did: select any plant, press Guide the arm, move the hand "
            "with the mouse and with the keys, close and open it, then press Escape. A "
            "cancelled try is not kept and uses none of your 15 minutes."
        ),
    ),
    "guided": Hand(
        code="guided",
        label="The tutor guides the arm for you",
        words=(
            "Select a plant and press Demonstrate: the arm is moved to it, and on to the "
            "bin, as a person would move it."
        ),
        trainee_moves=False,
        mistake_menu=True,
        controls=(
            ("click a plant on the tray map", (), "choose the plant to demonstrate"),
            ("the Mistake menu", (), "optionally, a mistake the hand makes on purpose"),
            ("the Demonstrate button", (), "the tutor guides the arm to the plant and the bin"),
        ),
        try_it=(
            "There is nothing to practise with the hand itself: choose your plants well. "
            "The Mistake menu shows what a demonstration to the wrong plant or a sloppy "
            "grab teaches the robot."
        ),
    ),
}


def check_hand(value, what: str = "the hand") -> str:
    """``value`` as a hand's code (any case, spaces trimmed).

    Raises
    ------
    InvalidParameterError
        ``value`` is not text or not one of the hands; the message lists them.
    """
    choices = ", ".join(f"{code!r} ({hand.label.lower()})" for code, hand in HANDS.items())
    if not isinstance(value, str):
        raise InvalidParameterError(
            f"{what} must be text, one of {choices}; got {type(value).__name__} {value!r:.40}"
        )
    code = value.strip().lower()
    if code not in HANDS:
        raise InvalidParameterError(f"{what} is {value.strip()[:40]!r}: write one of {choices}")
    return code


def hand_from_env() -> str | None:
    """The hand set by the educator in ``TUTOR_HAND``, or None when it is unset.

    Raises
    ------
    InvalidParameterError
        It is set to something that is not a hand (unset it to use the default).
    """
    value = env_text(HAND_ENV)
    if not value:
        return None
    return check_hand(value, f"{HAND_ENV} (set by your educator)")


#: where a chosen hand came from -> how the start form says it
HAND_SOURCES = {
    "explicit": "you chose it",
    "plan": "your educator's class plan sets it",
    "env": f"your educator set it ({HAND_ENV})",
    "default": "the default",
    "no-view": "there is no 3-D view to guide the arm in",
}


def hand_and_source(plan_hand=None, explicit=None) -> tuple[str, str]:
    """The hand a run uses and where it came from (a key of :data:`HAND_SOURCES`):
    ``explicit`` > the class plan's ``plan_hand`` > ``TUTOR_HAND`` > :data:`DEFAULT_HAND`.

    Raises
    ------
    InvalidParameterError
        As :func:`choose_hand`.
    """
    asked = (
        (explicit, "explicit", "the hand asked for"),
        (plan_hand, "plan", "the class plan's hand"),
    )
    for value, source, what in asked:
        if value is not None and value != "":
            return check_hand(value, what), source
    from_env = hand_from_env()
    return (DEFAULT_HAND, "default") if from_env is None else (from_env, "env")


def choose_hand(plan_hand=None, explicit=None) -> str:
    """The hand a run uses: ``explicit`` > the class plan's ``plan_hand`` > ``TUTOR_HAND``
    > :data:`DEFAULT_HAND`. None (or "") means "not set" at each level.

    Raises
    ------
    InvalidParameterError
        The first hand that is set is not one of :data:`HANDS` (the message lists them).
    """
    return hand_and_source(plan_hand, explicit)[0]


#: the list laid out as two columns, each control beside what it does, whatever the page's
#: own CSS does to ``dl`` (JupyterLab floats its terms, which a wrapped term then pushes
#: the rest of the list out of line) and whatever line height the widget gives its text
_GRID = (
    " style='display: grid; grid-template-columns: minmax(8em, max-content) 1fr; "
    f"column-gap: 1.5em; row-gap: 0.2em; margin: 0.3em 0; {PROSE}'"
)
_CELL = " style='float: none; width: auto; margin: 0; padding: 0'"


def controls_html(hand) -> str:
    """The controls of ``hand`` (a :class:`Hand` or its code) as an accessible HTML block:
    a ``<dl>`` whose terms are the keys in ``<kbd>`` and whose details say what they do,
    under a heading naming the hand (CSS class ``lfd-controls``)."""
    hand = hand if isinstance(hand, Hand) else HANDS[check_hand(hand)]
    rows = []
    for gesture, keys, what in hand.controls:
        shown = _said(html.escape(gesture), keys, lambda key: f"<kbd>{html.escape(key)}</kbd>")
        rows.append(f"<dt{_CELL}>{shown}</dt><dd{_CELL}>{html.escape(what)}</dd>")
    return (
        f"<div class='lfd-controls' role='group' aria-label='{html.escape(hand.label)}: "
        f"controls'><p style='{PROSE}'><b>{html.escape(hand.label)}</b>. "
        f"{html.escape(hand.words)}</p>"
        f"<dl{_GRID}>{''.join(rows)}</dl></div>"
    )
