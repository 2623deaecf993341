"""Tests of gen_stubs.py and its parser dts.py on a small declarations file shaped like
@nativescript/types-android's: the Java it writes, and that javac compiles it (when javac is
installed)."""

import os
import shutil
import subprocess
import sys
import tempfile
import unittest

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import dts  # noqa: E402
import gen_stubs  # noqa: E402

DTS = '''/// <reference path="android-declarations.d.ts"/>

declare module android {
	export module demo {
		export class Widget extends android.demo.Base {
			public static class: java.lang.Class<android.demo.Widget>;
			public static MODE_FAST: 1;
			public static BIG: 4294967296;
			public static RATIO: 0.5;
			public static NAME: "widget";
			public static DEFAULT: android.demo.Widget;
			/** @since 30 */
			public static LEVEL: number;
			public size: number;
			public constructor(name: string);
			public getTimestamp(): number;
			public onEvent(param0: android.demo.Widget): void;
			public setItems(items: androidNative.Array<string>): void;
			public all(): java.util.Map<string, any>;
			public get(key: android.demo.Widget.Key<any>): any;
			public static parse(text: string): android.demo.Widget;
			public uses(other: android.demo.Other, x: org.xmlpull.v1.XmlPullParser): void;
		}
		export module Widget {
			export class Listener extends java.lang.Object {
				public static class: java.lang.Class<android.demo.Widget.Listener>;
				/**
				 * Constructs a new instance of the android.demo.Widget$Listener interface with the provided implementation. An empty constructor exists calling super() when extending the interface class.
				 */
				public constructor(implementation: {
					onEvent(param0: android.demo.Widget): void;
				});
				public constructor();
				public onEvent(param0: android.demo.Widget): void;
			}
			export class Key<T>  extends java.lang.Object {
				public static class: java.lang.Class<android.demo.Widget.Key<any>>;
				public getName(): string;
			}
			export class Style {
				public static class: java.lang.Class<android.demo.Widget.Style>;
				public static FILL: android.demo.Widget.Style;
				public static STROKE: android.demo.Widget.Style;
				public static values(): androidNative.Array<android.demo.Widget.Style>;
				public static valueOf(name: string): android.demo.Widget.Style;
			}
		}
	}
}

declare module android {
	export module demo {
		export abstract class Base extends java.io.FileInputStream implements java.io.Closeable {
			public static class: java.lang.Class<android.demo.Base>;
			public constructor(fd: number);
		}
		export class Other extends java.lang.Object {
			public static class: java.lang.Class<android.demo.Other>;
			public secret(): void;
		}
		export class Impl extends java.lang.Object implements android.demo.Widget.Listener {
			public static class: java.lang.Class<android.demo.Impl>;
			public constructor();
		}
		export class Unused extends java.lang.Object {
			public static class: java.lang.Class<android.demo.Unused>;
		}
		export class Keep extends java.lang.Object implements java.lang.annotation.Annotation {
			public static class: java.lang.Class<android.demo.Keep>;
			/**
			 * Constructs a new instance of the android.demo.Keep interface with the provided implementation. An empty constructor exists calling super() when extending the interface class.
			 */
			public constructor(implementation: {
				value(): androidNative.Array<string>;
				equals(param0: any): boolean;
			});
			public constructor();
			public value(): androidNative.Array<string>;
			public equals(param0: any): boolean;
		}
	}
}
'''

OVERRIDES = '''# test
android.demo.Widget#getTimestamp = long
android.demo.Widget#get = !public <T> T get(android.demo.Widget.Key<T> p0)
android.demo.Widget#size = float
'''


class GenStubsTest(unittest.TestCase):
    def setUp(self):
        self.tmp = tempfile.mkdtemp()
        self.dts = os.path.join(self.tmp, "a.d.ts")
        with open(self.dts, "w") as f:
            f.write(DTS)
        self.ov = os.path.join(self.tmp, "ov.txt")
        with open(self.ov, "w") as f:
            f.write(OVERRIDES)
        self.out = os.path.join(self.tmp, "out")

    def tearDown(self):
        shutil.rmtree(self.tmp)

    def gen(self, *roots):
        gen_stubs.main([self.dts, self.out, "--overrides", self.ov, *roots])

    def read(self, rel):
        with open(os.path.join(self.out, rel)) as f:
            return f.read()

    def test_parses_kinds(self):
        c = dts.parse(self.dts)
        self.assertTrue(c["android.demo.Widget.Listener"].interface)
        self.assertFalse(c["android.demo.Widget"].interface)
        self.assertTrue(c["android.demo.Widget.Style"].enum)
        self.assertEqual(c["android.demo.Widget.Key"].tparams, ["T"])
        self.assertEqual(c["android.demo.Widget.Key"].outer, "android.demo.Widget")
        self.assertTrue(c["android.demo.Base"].abstract)
        level = [m for m in c["android.demo.Widget"].members if m.name == "LEVEL"][0]
        self.assertEqual(level.since, 30)  # `/** @since N */` is kept (api_levels.py reads it)
        self.assertIsNone([m for m in c["android.demo.Widget"].members if m.name == "NAME"][0].since)

    def test_full_class_members_types_and_overrides(self):
        self.gen("android.demo.Widget")
        w = self.read("android/demo/Widget.java")
        self.assertIn("public class Widget extends android.demo.Base {", w)
        self.assertIn("public static final int MODE_FAST = 1;", w)
        self.assertIn("public static final long BIG = 4294967296L;", w)
        self.assertIn("public static final double RATIO = 0.5;", w)
        self.assertIn('public static final java.lang.String NAME = "widget";', w)
        # A static final without a value (like Build.VERSION.SDK_INT) is no compile-time constant:
        # Kotlin must read it at run time, not fold `if (SDK_INT >= N)` with the stub's 0.
        self.assertIn("public static final int LEVEL = Integer.valueOf((int) 0);", w)
        self.assertIn("public float size;", w)  # override
        self.assertIn("public long getTimestamp()", w)  # override
        self.assertIn("public <T> T get(android.demo.Widget.Key<T> p0)", w)  # generic restored
        self.assertIn("public void setItems(java.lang.String[] p0)", w)
        self.assertIn("public java.util.Map<java.lang.String, ?> all()", w)  # lost argument: wildcard
        self.assertIn("public static android.demo.Widget parse(java.lang.String p0)", w)
        self.assertIn("public Widget(java.lang.String p0)", w)
        # A one-method interface keeps its method abstract (Kotlin lambdas convert to it).
        self.assertIn("public static interface Listener {", w)
        self.assertIn("void onEvent(android.demo.Widget p0);", w)
        self.assertIn("public static enum Style {", w)
        self.assertIn("FILL, STROKE;", w)
        # Types outside the JDK and the declarations become Object.
        self.assertIn("public void uses(android.demo.Other p0, java.lang.Object p1)", w)

    def test_other_types_become_shells_and_unused_ones_are_left_out(self):
        self.gen("android.demo.Widget")
        other = self.read("android/demo/Other.java")
        self.assertIn("public class Other {", other)
        self.assertNotIn("secret", other)  # a shell: no members
        self.assertFalse(os.path.exists(os.path.join(self.out, "android/demo/Unused.java")))
        base = self.read("android/demo/Base.java")
        # Supertype of a full class: full itself; concrete, so Closeable's close() is added.
        # FileInputStream has no no-arg constructor: the stub's constructors call another.
        self.assertIn("public Base(int p0) { super((java.io.FileDescriptor) null); throw", base)
        self.assertIn("public void close()", base)

    def test_a_class_implementing_a_one_method_interface_gets_that_method(self):
        self.gen("android.demo.Impl")
        impl = self.read("android/demo/Impl.java")
        self.assertIn("public class Impl implements android.demo.Widget.Listener {", impl)
        self.assertIn("public void onEvent(android.demo.Widget p0)", impl)

    def test_annotations(self):
        self.gen("android.demo.Keep")
        k = self.read("android/demo/Keep.java")
        self.assertIn("public @interface Keep {", k)
        self.assertIn("java.lang.String[] value();", k)
        self.assertNotIn("equals", k)

    @unittest.skipUnless(shutil.which("javac"), "javac is not installed")
    def test_javac_compiles_the_stubs(self):
        self.gen("android.demo.Widget", "android.demo.Keep", "android.demo.Impl")
        files = [os.path.join(d, f) for d, _, fs in os.walk(self.out) for f in fs if f.endswith(".java")]
        use = os.path.join(self.tmp, "Use.java")
        with open(use, "w") as f:
            f.write("""class Use {
    @android.demo.Keep({"x"}) void m(android.demo.Widget w, android.demo.Widget.Key<String> k) {
        String s = w.get(k);
        long t = w.getTimestamp();
        android.demo.Widget.Listener l = x -> {};
        android.demo.Widget.Style st = android.demo.Widget.Style.STROKE;
    }
}
""")
        r = subprocess.run(["javac", "-d", os.path.join(self.tmp, "cls"), *files, use], capture_output=True, text=True)
        self.assertEqual(r.returncode, 0, r.stderr)
        # And a call the API does not have is an error.
        with open(use, "w") as f:
            f.write("class Use { void m(android.demo.Other o) { o.secret(); } }\n")
        r = subprocess.run(["javac", "-d", os.path.join(self.tmp, "cls"), *files, use], capture_output=True, text=True)
        self.assertNotEqual(r.returncode, 0)
        self.assertIn("secret", r.stderr)


if __name__ == "__main__":
    unittest.main()
