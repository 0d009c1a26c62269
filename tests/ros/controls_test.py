"""scripts/kincal_controls.py: CSV lines in, kincal.controls_t out (LCM memq in one
process): names in the model's order whatever the header's, the robot's stamps as
sender_utime, bad lines skipped and named."""

import argparse
import io
import os
import sys
import unittest
from contextlib import redirect_stderr

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.join(HERE, "..", "..", "scripts"))
import kincal_controls  # noqa: E402

TYPES = os.environ.get("KINCAL_LCM_TYPES")


class Pipe(unittest.TestCase):
    def run_pipe(self, text):
        import lcm

        controls_t = kincal_controls.import_types(TYPES)
        lc = lcm.LCM("memq://")
        got = []
        lc.subscribe("KINCAL_CONTROLS", lambda ch, data: got.append(controls_t.decode(data)))
        # The publisher shares the process's memq: hand it this LCM instance.
        orig = kincal_controls.ControlsPublisher.__init__

        def init(self, *a, **k):
            orig(self, *a, **k)
            self.lc = lc

        kincal_controls.ControlsPublisher.__init__ = init
        try:
            args = argparse.Namespace(model="diffdrive", url="memq://", channel="KINCAL_CONTROLS", lcm_types=TYPES)
            err = io.StringIO()
            with redirect_stderr(err):
                rc = kincal_controls.pipe(args, io.StringIO(text))
        finally:
            kincal_controls.ControlsPublisher.__init__ = orig
        while lc.handle_timeout(0) > 0:
            pass
        return rc, got, err.getvalue()

    def test_header_order_and_stamps(self):
        rc, got, err = self.run_pipe("t,omega_r,omega_l\n10.0,2.0,1.0\n10.02,2.5,1.5\n")
        self.assertEqual(rc, 0, err)
        self.assertEqual(len(got), 2)
        self.assertEqual(list(got[0].names), ["omega_l", "omega_r"])
        self.assertEqual(list(got[1].values), [1.5, 2.5])
        self.assertEqual(got[1].sender_utime, 10_020_000)
        self.assertEqual(got[0].model, "diffdrive")

    def test_bad_lines_are_named_and_skipped(self):
        rc, got, err = self.run_pipe("1.0,1,2\n1.1,1\n1.2,x,2\n0.9,1,2\n1.3,nan,2\n1.4,3,4\n")
        self.assertEqual(rc, 1)
        self.assertEqual([m.sender_utime for m in got], [1_000_000, 1_400_000])
        self.assertIn("line 2 skipped: 2 fields", err)
        self.assertIn("line 3 skipped", err)
        self.assertIn("line 4 skipped: time goes back", err)
        self.assertIn("line 5 skipped: a value is not finite", err)
        self.assertIn("2 messages sent on KINCAL_CONTROLS, 4 lines skipped", err)


class DocsExample(unittest.TestCase):
    def test_the_cpp_example_in_the_docs_is_the_one_built_and_tested(self):
        root = os.path.join(HERE, "..", "..")
        with open(os.path.join(root, "apps", "examples", "controls_publisher.cc")) as f:
            code = f.read()
        with open(os.path.join(root, "docs", "ros.md")) as f:
            self.assertIn("```cpp\n" + code + "```", f.read())


if __name__ == "__main__":
    unittest.main()
