"""The one line naming the parameters that break loop closure, grouped by loop (issue 36)."""

from __future__ import annotations

from pincal.sensitivity import closure_line

LEG = ("a.tx", "a.ty", "b.rx")
SHARED = ("s.tx",)
LOOPS = (("p↔q", LEG + SHARED), ("r↔t", ("c.tx", "d.ry", *SHARED)), ("u↔v", ("e.tz",)))


def test_without_loops_the_parameters_are_said_by_joint():
    line = closure_line(list(LEG), max_joints=1)
    assert line.startswith("3 parameters break loop closure at 2 joints (")
    assert line.endswith(": a.{tx ty} and 1 more joint")


def test_on_one_loop_the_line_names_it():
    line = closure_line(list(LEG), LOOPS)
    assert line.startswith("3 parameters break loop closure at 2 joints of loop p↔q (")
    assert line.endswith(": a.{tx ty}, b.rx")
    one = closure_line(["e.tz"], LOOPS)
    assert one.startswith("1 parameter breaks loop closure in loop u↔v (")
    assert "after changing it;" in one


def test_each_loop_its_own_then_the_shared_ones():
    line = closure_line(["a.tx", "b.rx", "c.tx", "s.tx", "e.tz"], LOOPS, max_joints=2)
    head, groups = line.split(": ", 1)
    assert head.startswith("5 parameters break loop closure in 3 loops (")
    assert groups.split("; ") == [
        "loop p↔q: 2 at 2 joints (a.tx and 1 more joint)",
        "loop r↔t: 1 (c.tx)",
        "loop u↔v: 1 (e.tz)",
        "shared by loops p↔q, r↔t: 1 (s.tx)",
    ]


def test_shared_by_every_loop_and_a_name_on_no_loop():
    two = LOOPS[:2]
    line = closure_line(["a.tx", "c.tx", "s.tx"], two)
    assert line.endswith("; shared by both loops: 1 (s.tx)")
    # a name on no loop: the loops cannot be told, said by joint
    assert " at 2 joints (" in closure_line(["a.tx", "z.rx"], two)
