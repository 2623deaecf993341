"""Unit tests of api_levels.py (run by test-api-levels.sh: python3 -m unittest test_api_levels)."""
import unittest

import api_levels as al

# A method as dexdump -d prints it: `if (SDK_INT >= 33) a() else b()`, then c().
GUARDED = """\
  Class descriptor  : 'Lp/C;'
  Superclass        : 'Ljava/lang/Object;'
  Direct methods    -
    #0              : (in Lp/C;)
      name          : 'f'
      type          : '()V'
000100:                                        |[000100] p.C.f:()V
000110: 6000 0000                              |0000: sget v0, Landroid/os/Build$VERSION;.SDK_INT:I // field@0000
000114: 1301 2100                              |0002: const/16 v1, #int 33 // #21
000118: 3510 0600                              |0004: if-lt v0, v1, 000a // +0006
00011c: 7100 0100 0000                         |0006: invoke-static {}, Lq/A;.a:()V // method@0001
000122: 2803                                   |0009: goto 000c // +0003
000124: 7100 0200 0000                         |000a: invoke-static {}, Lq/A;.b:()V // method@0002
00012a: 7100 0300 0000                         |000c: invoke-static {}, Lq/A;.c:()V // method@0003
000130: 0e00                                   |000f: return-void
      catches       : (none)
"""


class Descriptors(unittest.TestCase):
    def test_split(self):
        self.assertEqual(al.split_desc("(I[Ljava/lang/String;J)V"), (["I", "[Ljava/lang/String;", "J"], "V"))
        self.assertEqual(al.split_desc("Ljava/lang/Object;"), (None, "Ljava/lang/Object;"))

    def test_types(self):
        self.assertTrue(al.ts_matches("number", "J"))
        self.assertFalse(al.ts_matches("number", "Ljava/lang/String;"))
        self.assertTrue(al.ts_matches("string", "Ljava/lang/CharSequence;"))
        self.assertFalse(al.ts_matches("string", "I"))
        self.assertTrue(al.ts_matches("androidNative.Array<number>", "[F"))
        self.assertTrue(al.ts_matches("java.util.List<any>", "Ljava/util/List;"))
        self.assertFalse(al.ts_matches("java.nio.Buffer", "Ljava/nio/ByteBuffer;"))
        self.assertTrue(al.ts_matches("android.os.Build.VERSION", "Landroid/os/Build$VERSION;"))

    def test_api_impl(self):
        self.assertEqual(al.api_impl_level("io/ecvo/app/MainActivity$Api30Impl"), 30)
        self.assertEqual(al.api_impl_level("io/ecvo/app/MainActivity$Api30Impl$run$1"), 30)
        self.assertIsNone(al.api_impl_level("io/ecvo/app/MyApi30"))


class Guards(unittest.TestCase):
    def setUp(self):
        classes, methods = al.parse_dexdump(GUARDED)
        self.assertIn("p/C", classes)
        self.m = methods[0]

    def test_parse(self):
        self.assertEqual([op for _, op, _ in self.m.insns][:3], ["sget", "const/16", "if-lt"])

    def test_bounds(self):
        b = dict(zip([a for a, _, _ in self.m.insns], al.guard_bounds(self.m, 26)))
        self.assertEqual(b[0x6], 33)  # the then-branch
        self.assertEqual(b[0xA], 26)  # the else-branch
        self.assertEqual(b[0xC], 26)  # after the join

    def test_clobbered_register_is_no_guard(self):
        text = GUARDED.replace("|0002: const/16 v1, #int 33", "|0002: const/16 v1, #int 33").replace(
            "|0004: if-lt v0, v1", "|0004: if-lt v2, v1")
        m = al.parse_dexdump(text)[1][0]
        b = dict(zip([a for a, _, _ in m.insns], al.guard_bounds(m, 26)))
        self.assertEqual(b[0x6], 26)

    def test_reversed_operands(self):
        # if-gt v1(33), v0(sdk) jumps when 33 > SDK_INT: the fall-through has SDK_INT >= 33.
        m = al.parse_dexdump(GUARDED.replace("if-lt v0, v1", "if-gt v1, v0"))[1][0]
        b = dict(zip([a for a, _, _ in m.insns], al.guard_bounds(m, 26)))
        self.assertEqual(b[0x6], 33)
        self.assertEqual(b[0xA], 26)


if __name__ == "__main__":
    unittest.main()
