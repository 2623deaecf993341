// Also rewrites calls of the Java 9+ covariant java.nio buffer methods (see covariantBuffer).
// Rewrites every invokedynamic that bootstraps through java.lang.invoke.LambdaMetafactory
// into a plain class, so that Android's dx (which does not desugar) writes no invoke-custom.
// Used by scripts/android/build-apk.sh on the shrunk app + kotlin-stdlib jar; see
// docs/android-apk.md.
//
// For a call site `invokedynamic name(C1..Ck)I` with bootstrap arguments
// (samType, implHandle, instantiatedType) it generates `Owner$$Desugared$N implements I`
// holding the k captured values, with a static factory `create(C1..Ck)I` that replaces the
// invokedynamic (same stack effect), and the method `name` + samType that loads the captured
// values and the SAM arguments, converts them (cast, box, unbox) to the implementation's
// parameter types, calls the implementation and converts the result back. A private
// implementation method is made package-private so that the generated class (same package)
// can call it. Anything else (another bootstrap, altMetafactory with flags, serializable
// lambdas, conversions it does not know) is an error: the tool fails rather than guess.
//
// Usage: java -cp asm.jar:asm-tree.jar:. LambdaDesugar IN.jar OUT.jar
// Prints one line per rewritten call site and a summary to stderr.
import java.io.ByteArrayOutputStream;
import java.io.FileInputStream;
import java.io.FileOutputStream;
import java.io.IOException;
import java.io.InputStream;
import java.util.ArrayList;
import java.util.HashSet;
import java.util.LinkedHashMap;
import java.util.List;
import java.util.Map;
import java.util.Set;
import java.util.zip.ZipEntry;
import java.util.zip.ZipInputStream;
import java.util.zip.ZipOutputStream;
import org.objectweb.asm.ClassReader;
import org.objectweb.asm.ClassWriter;
import org.objectweb.asm.Handle;
import org.objectweb.asm.MethodVisitor;
import org.objectweb.asm.Opcodes;
import org.objectweb.asm.Type;
import org.objectweb.asm.tree.AbstractInsnNode;
import org.objectweb.asm.tree.ClassNode;
import org.objectweb.asm.tree.InvokeDynamicInsnNode;
import org.objectweb.asm.tree.MethodInsnNode;
import org.objectweb.asm.tree.MethodNode;
import org.objectweb.asm.tree.TypeInsnNode;

public final class LambdaDesugar {
    private static final String LMF = "java/lang/invoke/LambdaMetafactory";

    public static void main(String[] args) throws IOException {
        if (args.length != 2) {
            System.err.println("usage: LambdaDesugar IN.jar OUT.jar");
            System.exit(2);
        }
        Map<String, byte[]> entries = new LinkedHashMap<>();
        try (ZipInputStream in = new ZipInputStream(new FileInputStream(args[0]))) {
            for (ZipEntry e; (e = in.getNextEntry()) != null; ) {
                if (!e.isDirectory()) entries.put(e.getName(), readAll(in));
            }
        }
        Map<String, ClassNode> classes = new LinkedHashMap<>();
        for (Map.Entry<String, byte[]> e : entries.entrySet()) {
            if (!e.getKey().endsWith(".class")) continue;
            ClassNode cn = new ClassNode();
            new ClassReader(e.getValue()).accept(cn, 0);
            classes.put(cn.name, cn);
        }
        List<ClassNode> generated = new ArrayList<>();
        Set<String> touched = new HashSet<>();
        java.util.Set<String> modified = new java.util.HashSet<>();
        int sites = 0, buffers = 0;
        for (ClassNode cn : classes.values()) {
            int n = 0;
            for (MethodNode m : cn.methods) {
                for (AbstractInsnNode insn = m.instructions.getFirst(); insn != null; insn = insn.getNext()) {
                    if (insn instanceof MethodInsnNode && covariantBuffer((MethodInsnNode) insn)) {
                        MethodInsnNode mi = (MethodInsnNode) insn;
                        String ret = Type.getReturnType(mi.desc).getInternalName();
                        mi.desc = mi.desc.substring(0, mi.desc.indexOf(')') + 1) + "Ljava/nio/Buffer;";
                        TypeInsnNode cast = new TypeInsnNode(Opcodes.CHECKCAST, ret);
                        m.instructions.insert(mi, cast);
                        insn = cast;
                        modified.add(cn.name);
                        buffers++;
                        continue;
                    }
                    if (!(insn instanceof InvokeDynamicInsnNode)) continue;
                    InvokeDynamicInsnNode indy = (InvokeDynamicInsnNode) insn;
                    String where = cn.name + "." + m.name + m.desc;
                    if (!indy.bsm.getOwner().equals(LMF) || !indy.bsm.getName().equals("metafactory")) {
                        fail(where + ": invokedynamic with bootstrap " + indy.bsm.getOwner() + "."
                                + indy.bsm.getName() + " is not supported");
                    }
                    String lambdaName = cn.name + "$$Desugared$" + (n++);
                    while (classes.containsKey(lambdaName)) lambdaName += "_";
                    generated.add(lambdaClass(lambdaName, indy, classes, where));
                    modified.add(cn.name);
                    modified.add(((Handle) indy.bsmArgs[1]).getOwner());
                    MethodInsnNode call = new MethodInsnNode(Opcodes.INVOKESTATIC, lambdaName, "create", indy.desc, false);
                    m.instructions.set(indy, call);
                    touched.add(cn.name);
                    touched.add(((Handle) indy.bsmArgs[1]).getOwner()); // its access may change
                    insn = call;
                    sites++;
                    System.err.println("[desugar] " + where + " -> " + lambdaName);
                }
            }
        }
        try (ZipOutputStream out = new ZipOutputStream(new FileOutputStream(args[1]))) {
            for (Map.Entry<String, byte[]> e : entries.entrySet()) {
                byte[] data = e.getValue();
                if (e.getKey().endsWith(".class")) {
                    ClassNode cn = classes.get(e.getKey().substring(0, e.getKey().length() - 6));
                    if (cn == null) fail("class file name " + e.getKey() + " does not match its class");
                    // Untouched classes are copied byte for byte. A changed class keeps its
                    // max stack/locals: an invokestatic with the invokedynamic's descriptor has
                    // the same stack effect (ASM's COMPUTE_MAXS gets some of kotlin-stdlib's
                    // proguard-shrunk methods wrong, and dx then rejects them).
                    if (modified.contains(cn.name)) data = write(cn, 0);
                }
                out.putNextEntry(new ZipEntry(e.getKey()));
                out.write(data);
                out.closeEntry();
            }
            for (ClassNode cn : generated) {
                out.putNextEntry(new ZipEntry(cn.name + ".class"));
                out.write(write(cn, ClassWriter.COMPUTE_MAXS));
                out.closeEntry();
            }
        }
        System.err.println("[desugar] " + buffers + " covariant java.nio buffer calls rewritten to Buffer's");
        System.err.println("[desugar] " + sites + " LambdaMetafactory call sites rewritten into "
                + generated.size() + " classes");
    }

    private static ClassNode lambdaClass(String name, InvokeDynamicInsnNode indy, Map<String, ClassNode> classes,
                                         String where) {
        if (indy.bsmArgs.length != 3) fail(where + ": metafactory with " + indy.bsmArgs.length + " arguments");
        Type samType = (Type) indy.bsmArgs[0];
        Handle impl = (Handle) indy.bsmArgs[1];
        Type instType = (Type) indy.bsmArgs[2];
        Type[] captured = Type.getArgumentTypes(indy.desc);
        Type iface = Type.getReturnType(indy.desc);

        ClassNode cn = new ClassNode();
        cn.visit(Opcodes.V1_8, Opcodes.ACC_FINAL | Opcodes.ACC_SYNTHETIC | Opcodes.ACC_SUPER, name, null,
                "java/lang/Object", new String[] {iface.getInternalName()});
        for (int i = 0; i < captured.length; i++) {
            cn.visitField(Opcodes.ACC_PRIVATE | Opcodes.ACC_FINAL, "f" + i, captured[i].getDescriptor(), null, null);
        }
        // Constructor and factory.
        String ctorDesc = Type.getMethodDescriptor(Type.VOID_TYPE, captured);
        MethodVisitor mv = cn.visitMethod(Opcodes.ACC_PRIVATE, "<init>", ctorDesc, null, null);
        mv.visitCode();
        mv.visitVarInsn(Opcodes.ALOAD, 0);
        mv.visitMethodInsn(Opcodes.INVOKESPECIAL, "java/lang/Object", "<init>", "()V", false);
        int slot = 1;
        for (int i = 0; i < captured.length; i++) {
            mv.visitVarInsn(Opcodes.ALOAD, 0);
            mv.visitVarInsn(captured[i].getOpcode(Opcodes.ILOAD), slot);
            mv.visitFieldInsn(Opcodes.PUTFIELD, name, "f" + i, captured[i].getDescriptor());
            slot += captured[i].getSize();
        }
        mv.visitInsn(Opcodes.RETURN);
        mv.visitMaxs(0, 0);
        mv.visitEnd();
        mv = cn.visitMethod(Opcodes.ACC_STATIC, "create", indy.desc, null, null);
        mv.visitCode();
        mv.visitTypeInsn(Opcodes.NEW, name);
        mv.visitInsn(Opcodes.DUP);
        slot = 0;
        for (Type t : captured) {
            mv.visitVarInsn(t.getOpcode(Opcodes.ILOAD), slot);
            slot += t.getSize();
        }
        mv.visitMethodInsn(Opcodes.INVOKESPECIAL, name, "<init>", ctorDesc, false);
        mv.visitInsn(Opcodes.ARETURN);
        mv.visitMaxs(0, 0);
        mv.visitEnd();

        // The interface method.
        Type[] samArgs = samType.getArgumentTypes();
        Type[] instArgs = instType.getArgumentTypes();
        if (samArgs.length != instArgs.length) fail(where + ": SAM and instantiated types differ in arity");
        List<Type> target = new ArrayList<>();
        int tag = impl.getTag();
        boolean isNew = tag == Opcodes.H_NEWINVOKESPECIAL;
        if (tag != Opcodes.H_INVOKESTATIC && !isNew) target.add(Type.getObjectType(impl.getOwner()));
        for (Type t : Type.getArgumentTypes(impl.getDesc())) target.add(t);
        if (target.size() != captured.length + samArgs.length) {
            fail(where + ": " + captured.length + " captured + " + samArgs.length
                    + " SAM arguments for an implementation taking " + target.size());
        }
        mv = cn.visitMethod(Opcodes.ACC_PUBLIC, indy.name, samType.getDescriptor(), null, null);
        mv.visitCode();
        if (isNew) {
            mv.visitTypeInsn(Opcodes.NEW, impl.getOwner());
            mv.visitInsn(Opcodes.DUP);
        }
        for (int i = 0; i < captured.length; i++) {
            mv.visitVarInsn(Opcodes.ALOAD, 0);
            mv.visitFieldInsn(Opcodes.GETFIELD, name, "f" + i, captured[i].getDescriptor());
            convert(mv, captured[i], captured[i], target.get(i), where);
        }
        slot = 1;
        for (int j = 0; j < samArgs.length; j++) {
            mv.visitVarInsn(samArgs[j].getOpcode(Opcodes.ILOAD), slot);
            slot += samArgs[j].getSize();
            convert(mv, samArgs[j], instArgs[j], target.get(captured.length + j), where);
        }
        Type implRet;
        switch (tag) {
            case Opcodes.H_INVOKESTATIC:
                mv.visitMethodInsn(Opcodes.INVOKESTATIC, impl.getOwner(), impl.getName(), impl.getDesc(), impl.isInterface());
                implRet = Type.getReturnType(impl.getDesc());
                break;
            case Opcodes.H_INVOKEVIRTUAL:
            case Opcodes.H_INVOKESPECIAL: // a private instance method, made package-private below
                mv.visitMethodInsn(impl.isInterface() ? Opcodes.INVOKEINTERFACE : Opcodes.INVOKEVIRTUAL,
                        impl.getOwner(), impl.getName(), impl.getDesc(), impl.isInterface());
                implRet = Type.getReturnType(impl.getDesc());
                break;
            case Opcodes.H_INVOKEINTERFACE:
                mv.visitMethodInsn(Opcodes.INVOKEINTERFACE, impl.getOwner(), impl.getName(), impl.getDesc(), true);
                implRet = Type.getReturnType(impl.getDesc());
                break;
            case Opcodes.H_NEWINVOKESPECIAL:
                mv.visitMethodInsn(Opcodes.INVOKESPECIAL, impl.getOwner(), "<init>", impl.getDesc(), false);
                implRet = Type.getObjectType(impl.getOwner());
                break;
            default:
                fail(where + ": implementation handle kind " + tag + " is not supported");
                return null;
        }
        Type samRet = samType.getReturnType();
        if (samRet.getSort() == Type.VOID) {
            if (implRet.getSize() == 2) mv.visitInsn(Opcodes.POP2);
            else if (implRet.getSize() == 1) mv.visitInsn(Opcodes.POP);
            mv.visitInsn(Opcodes.RETURN);
        } else {
            if (implRet.getSort() == Type.VOID) fail(where + ": a void implementation for a non-void SAM");
            convert(mv, implRet, implRet, samRet, where);
            mv.visitInsn(samRet.getOpcode(Opcodes.IRETURN));
        }
        mv.visitMaxs(0, 0);
        mv.visitEnd();

        // The generated class is in the owner's package: a private target must become package-private.
        if (!samePackage(name, impl.getOwner())) fail(where + ": implementation in another package");
        ClassNode owner = classes.get(impl.getOwner());
        if (owner != null) {
            for (MethodNode m : owner.methods) {
                if (m.name.equals(isNew ? "<init>" : impl.getName()) && m.desc.equals(impl.getDesc())) {
                    m.access &= ~Opcodes.ACC_PRIVATE;
                    // Interface methods cannot be package-private.
                    if ((owner.access & Opcodes.ACC_INTERFACE) != 0) m.access |= Opcodes.ACC_PUBLIC;
                }
            }
            if (isNew || tag == Opcodes.H_INVOKESPECIAL) {
                // invokespecial on a private method becomes invokevirtual: rewrite other such calls.
                for (MethodNode m : owner.methods) {
                    for (AbstractInsnNode i = m.instructions.getFirst(); i != null; i = i.getNext()) {
                        if (i instanceof MethodInsnNode && !isNew) {
                            MethodInsnNode mi = (MethodInsnNode) i;
                            if (mi.getOpcode() == Opcodes.INVOKESPECIAL && mi.owner.equals(impl.getOwner())
                                    && mi.name.equals(impl.getName()) && mi.desc.equals(impl.getDesc())) {
                                mi.setOpcode(Opcodes.INVOKEVIRTUAL);
                            }
                        }
                    }
                }
            }
        } else if (tag == Opcodes.H_INVOKESPECIAL) {
            fail(where + ": private implementation " + impl.getOwner() + "." + impl.getName() + " outside the jar");
        }
        return cn;
    }

    private static final Set<String> BUFFER_METHODS = new HashSet<>(java.util.Arrays.asList(
            "position", "limit", "mark", "reset", "clear", "flip", "rewind"));

    /**
     * A call of a java.nio buffer's covariant override (Java 9+: ByteBuffer.position(int) returns
     * ByteBuffer). Android declares them only in java.nio.Buffer (returning Buffer) at every API
     * level, so such a reference fails with NoSuchMethodError; code compiled against
     * android.jar calls the Buffer-returning method, which the rewrite restores (+ checkcast).
     */
    private static boolean covariantBuffer(MethodInsnNode mi) {
        if (mi.getOpcode() != Opcodes.INVOKEVIRTUAL || !mi.owner.startsWith("java/nio/")
                || !mi.owner.endsWith("Buffer") || mi.owner.equals("java/nio/Buffer")
                || !BUFFER_METHODS.contains(mi.name)) {
            return false;
        }
        Type ret = Type.getReturnType(mi.desc);
        return ret.getSort() == Type.OBJECT && ret.getInternalName().startsWith("java/nio/")
                && ret.getInternalName().endsWith("Buffer") && !ret.getInternalName().equals("java/nio/Buffer");
    }

    /** Converts the value on the stack from `from` (known to be `as` when a reference) to `to`. */
    private static void convert(MethodVisitor mv, Type from, Type as, Type to, String where) {
        boolean fromPrim = isPrimitive(from), toPrim = isPrimitive(to);
        if (!fromPrim && !toPrim) {
            if (!to.equals(Type.getObjectType("java/lang/Object")) && !to.equals(from)) {
                mv.visitTypeInsn(Opcodes.CHECKCAST, to.getInternalName());
            }
        } else if (!fromPrim) { // unbox: through the instantiated box type, else the target's box
            String boxName = as.getSort() == Type.OBJECT && unboxedOf(as.getInternalName()) != null
                    ? as.getInternalName() : boxOf(to).getInternalName();
            Type unboxed = unboxedOf(boxName);
            mv.visitTypeInsn(Opcodes.CHECKCAST, boxName);
            mv.visitMethodInsn(Opcodes.INVOKEVIRTUAL, boxName, unboxed.getClassName() + "Value",
                    "()" + unboxed.getDescriptor(), false);
            widen(mv, unboxed, to, where);
        } else if (!toPrim) { // box
            Type box = boxOf(from);
            mv.visitMethodInsn(Opcodes.INVOKESTATIC, box.getInternalName(), "valueOf",
                    "(" + from.getDescriptor() + ")" + box.getDescriptor(), false);
            if (!to.equals(box) && !to.getInternalName().equals("java/lang/Object")) {
                mv.visitTypeInsn(Opcodes.CHECKCAST, to.getInternalName());
            }
        } else {
            widen(mv, from, to, where);
        }
    }

    private static void widen(MethodVisitor mv, Type from, Type to, String where) {
        if (from.equals(to)) return;
        int f = from.getSort(), t = to.getSort();
        boolean intLike = f == Type.INT || f == Type.SHORT || f == Type.BYTE || f == Type.CHAR;
        if (intLike && (t == Type.INT || (t == Type.SHORT && f == Type.BYTE))) return;
        if (intLike && t == Type.LONG) mv.visitInsn(Opcodes.I2L);
        else if (intLike && t == Type.FLOAT) mv.visitInsn(Opcodes.I2F);
        else if (intLike && t == Type.DOUBLE) mv.visitInsn(Opcodes.I2D);
        else if (f == Type.LONG && t == Type.FLOAT) mv.visitInsn(Opcodes.L2F);
        else if (f == Type.LONG && t == Type.DOUBLE) mv.visitInsn(Opcodes.L2D);
        else if (f == Type.FLOAT && t == Type.DOUBLE) mv.visitInsn(Opcodes.F2D);
        else fail(where + ": no widening from " + from + " to " + to);
    }

    private static boolean isPrimitive(Type t) {
        return t.getSort() != Type.OBJECT && t.getSort() != Type.ARRAY && t.getSort() != Type.VOID;
    }

    private static Type boxOf(Type prim) {
        switch (prim.getSort()) {
            case Type.BOOLEAN: return Type.getObjectType("java/lang/Boolean");
            case Type.BYTE: return Type.getObjectType("java/lang/Byte");
            case Type.CHAR: return Type.getObjectType("java/lang/Character");
            case Type.SHORT: return Type.getObjectType("java/lang/Short");
            case Type.INT: return Type.getObjectType("java/lang/Integer");
            case Type.LONG: return Type.getObjectType("java/lang/Long");
            case Type.FLOAT: return Type.getObjectType("java/lang/Float");
            case Type.DOUBLE: return Type.getObjectType("java/lang/Double");
            default: return null;
        }
    }

    private static Type unboxedOf(String box) {
        switch (box) {
            case "java/lang/Boolean": return Type.BOOLEAN_TYPE;
            case "java/lang/Byte": return Type.BYTE_TYPE;
            case "java/lang/Character": return Type.CHAR_TYPE;
            case "java/lang/Short": return Type.SHORT_TYPE;
            case "java/lang/Integer": return Type.INT_TYPE;
            case "java/lang/Long": return Type.LONG_TYPE;
            case "java/lang/Float": return Type.FLOAT_TYPE;
            case "java/lang/Double": return Type.DOUBLE_TYPE;
            default: return null;
        }
    }

    private static boolean samePackage(String a, String b) {
        return a.substring(0, Math.max(0, a.lastIndexOf('/'))).equals(b.substring(0, Math.max(0, b.lastIndexOf('/'))));
    }

    private static byte[] write(ClassNode cn, int flags) {
        ClassWriter cw = new ClassWriter(flags);
        cn.accept(cw);
        return cw.toByteArray();
    }

    private static byte[] readAll(InputStream in) throws IOException {
        ByteArrayOutputStream out = new ByteArrayOutputStream();
        byte[] buf = new byte[65536];
        for (int r; (r = in.read(buf)) > 0; ) out.write(buf, 0, r);
        return out.toByteArray();
    }

    private static void fail(String msg) {
        System.err.println("[desugar] error: " + msg);
        System.exit(1);
    }
}
