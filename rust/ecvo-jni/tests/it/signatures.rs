//! The Kotlin declarations in `NativeBridge.kt` and the Rust `native_method!`
//! declarations must name the same methods with the same JNI signatures.

use std::collections::BTreeMap;
use std::path::Path;

/// The JNI descriptor of a Kotlin parameter or return type.
fn descriptor(kotlin: &str) -> String {
    match kotlin.trim().trim_end_matches('?') {
        "Int" => "I".into(),
        "Long" => "J".into(),
        "Double" => "D".into(),
        "Float" => "F".into(),
        "Boolean" => "Z".into(),
        "Short" => "S".into(),
        "Byte" => "B".into(),
        "Unit" => "V".into(),
        "ShortArray" => "[S".into(),
        "ByteArray" => "[B".into(),
        "FloatArray" => "[F".into(),
        "DoubleArray" => "[D".into(),
        "IntArray" => "[I".into(),
        "LongArray" => "[J".into(),
        "ByteBuffer" => "Ljava/nio/ByteBuffer;".into(),
        "String" => "Ljava/lang/String;".into(),
        other => panic!("add the Kotlin type `{other}` to this test"),
    }
}

/// `name -> signature` of every `external fun` in a Kotlin source.
fn kotlin_natives(src: &str) -> BTreeMap<String, String> {
    // Drop comments (the KDoc mentions `external fun`-like text).
    let mut code = String::new();
    let mut rest = src;
    while let Some(i) = rest.find("/*") {
        code.push_str(&rest[..i]);
        rest = &rest[i + rest[i..].find("*/").expect("closed comment") + 2..];
    }
    code.push_str(rest);
    let code: String = code
        .lines()
        .map(|l| l.split("//").next().unwrap_or(""))
        .collect::<Vec<_>>()
        .join("\n");

    let mut out = BTreeMap::new();
    for part in code.split("external fun ").skip(1) {
        let open = part.find('(').expect("parameter list");
        let name = part[..open].trim().to_string();
        let mut depth = 0;
        let mut close = open;
        for (i, c) in part.char_indices().skip(open) {
            match c {
                '(' => depth += 1,
                ')' => {
                    depth -= 1;
                    if depth == 0 {
                        close = i;
                        break;
                    }
                }
                _ => {}
            }
        }
        let params: String = part[open + 1..close]
            .split(',')
            .filter(|p| !p.trim().is_empty())
            .map(|p| descriptor(p.split(':').nth(1).expect("typed parameter")))
            .collect();
        let after = part[close + 1..].trim_start();
        let ret = match after.strip_prefix(':') {
            Some(r) => descriptor(r.split_whitespace().next().expect("return type")),
            None => "V".into(),
        };
        assert!(
            out.insert(name.clone(), format!("({params}){ret}"))
                .is_none(),
            "overloaded native `{name}`"
        );
    }
    out
}

#[test]
fn rust_and_kotlin_declare_the_same_native_methods() {
    let kt = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../android-app/tracker/src/main/kotlin/io/ecvo/NativeBridge.kt");
    let src = std::fs::read_to_string(&kt).expect("NativeBridge.kt");
    assert!(src.contains("package io.ecvo") && src.contains("object NativeBridge"));
    let kotlin = kotlin_natives(&src);
    assert_eq!(kotlin.len(), 19, "NativeBridge.kt: {kotlin:?}");
    assert!(
        src.matches("@JvmStatic external fun").count() == 19,
        "every native must be @JvmStatic (the Rust side is static)"
    );

    let rust: BTreeMap<String, String> = ecvo_jni::declared_signatures()
        .into_iter()
        .map(|(export, sig)| {
            let name = export
                .strip_prefix("Java_io_ecvo_NativeBridge_")
                .expect("short JNI name of io.ecvo.NativeBridge");
            (name.to_string(), sig)
        })
        .collect();
    assert_eq!(rust.len(), ecvo_jni::NATIVE_METHODS.len());
    assert_eq!(
        kotlin, rust,
        "NativeBridge.kt (left) and ecvo-jni (right) disagree"
    );
}

/// The JNI descriptor of a Java parameter or return type.
fn java_descriptor(java: &str) -> String {
    match java.trim() {
        "int" => "I".into(),
        "long" => "J".into(),
        "double" => "D".into(),
        "float" => "F".into(),
        "boolean" => "Z".into(),
        "short" => "S".into(),
        "byte" => "B".into(),
        "void" => "V".into(),
        "short[]" => "[S".into(),
        "byte[]" => "[B".into(),
        "float[]" => "[F".into(),
        "double[]" => "[D".into(),
        "ByteBuffer" => "Ljava/nio/ByteBuffer;".into(),
        other => panic!("add the Java type `{other}` to this test"),
    }
}

/// The Java twin of `NativeBridge` used by the JNI drivers (`tests/drivers`) binds the
/// same exported symbols by their short names, which carry no signature: a missing
/// parameter is not a link error but garbage read by the native side (it happened:
/// the drivers once passed 13 arguments to the 14 of `nativeInit`). Each of its
/// natives must have the Rust declaration's signature.
#[test]
fn the_drivers_java_twin_declares_the_same_signatures() {
    let java =
        Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/drivers/io/ecvo/NativeBridge.java");
    let src = std::fs::read_to_string(&java).expect("NativeBridge.java");
    let rust: BTreeMap<String, String> = ecvo_jni::declared_signatures()
        .into_iter()
        .map(|(export, sig)| {
            let name = export.strip_prefix("Java_io_ecvo_NativeBridge_").unwrap();
            (name.to_string(), sig)
        })
        .collect();
    let mut seen = 0;
    for decl in src.split("public static native ").skip(1) {
        let decl = &decl[..decl.find(';').expect("declaration ends with ;")];
        let open = decl.find('(').expect("parameter list");
        let close = decl.rfind(')').expect("parameter list");
        let mut head = decl[..open].split_whitespace();
        let ret = java_descriptor(head.next().expect("return type"));
        let name = head.next().expect("method name");
        let params: String = decl[open + 1..close]
            .split(',')
            .filter(|p| !p.trim().is_empty())
            .map(|p| {
                let p = p.split_whitespace().collect::<Vec<_>>();
                java_descriptor(p[..p.len() - 1].join(" ").as_str())
            })
            .collect();
        let sig = format!("({params}){ret}");
        assert_eq!(
            rust.get(name),
            Some(&sig),
            "NativeBridge.java's {name} (right) disagrees with ecvo-jni (left)"
        );
        seen += 1;
    }
    assert!(
        seen >= 10,
        "parsed only {seen} natives from NativeBridge.java"
    );
}
