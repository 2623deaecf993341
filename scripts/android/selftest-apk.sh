# shellcheck shell=bash
# check-apk.sh --selftest: sourced by check-apk.sh (uses its check_apk, $APK, log, die).
# Each broken copy of $APK must fail exactly the checks listed for it; an intact copy (re-zipped
# and re-signed the same way) must pass, so a failure is the defect's and not the re-packing's.
ST="$(mktemp -d)"
trap 'rm -rf "$ST"' EXIT
BULLSEYE="${ECVO_APK_CACHE:-${XDG_CACHE_HOME:-$HOME/.cache}/ecvo/apk-tools}/bullseye"
DX_JAR="$BULLSEYE/root/usr/share/java/com.android.dx.jar"
[ -f "$DX_JAR" ] || die "no $DX_JAR (run build-apk.sh first: it installs dx)"
FRAMEWORK=/usr/share/android-framework-res/framework-res.apk

keytool -genkeypair -keystore "$ST/k.jks" -storepass selftest -keypass selftest -alias k -keyalg RSA \
  -keysize 2048 -validity 2 -dname "CN=check-apk selftest" >/dev/null 2>&1 || die "keytool failed"

# Two small dex files: one whose only class uses a lambda (dx writes invoke-custom at
# --min-sdk-version 26), one with a plain class.
mkdir -p "$ST/j/lam" "$ST/j/plain"
cat > "$ST/j/Lam.java" <<'EOF'
public class Lam { public static Runnable r() { return () -> System.out.println("x"); } }
EOF
cat > "$ST/j/Plain.java" <<'EOF'
public class Plain { public static int one() { return 1; } }
EOF
javac -nowarn --release 8 -d "$ST/j/lam" "$ST/j/Lam.java" && javac -nowarn --release 8 -d "$ST/j/plain" "$ST/j/Plain.java" \
  || die "javac of the probes failed"
java -jar "$DX_JAR" --dex --min-sdk-version=26 --output="$ST/lambda.dex" "$ST/j/lam" || die "dx lambda probe"
java -jar "$DX_JAR" --dex --min-sdk-version=26 --output="$ST/plain.dex" "$ST/j/plain" || die "dx plain probe"

# A manifest with minSdk 24, no launcher and no permission (for the badging check).
mkdir -p "$ST/m"
cat > "$ST/m/AndroidManifest.xml" <<'EOF'
<?xml version="1.0" encoding="utf-8"?>
<manifest xmlns:android="http://schemas.android.com/apk/res/android" package="io.ecvo.app">
    <uses-sdk android:minSdkVersion="24" android:targetSdkVersion="35" />
    <application android:label="x"><activity android:name=".MainActivity" /></application>
</manifest>
EOF
aapt package -f -M "$ST/m/AndroidManifest.xml" -I "$FRAMEWORK" -F "$ST/m/base.apk" >/dev/null || die "aapt (probe manifest)"
unzip -p "$ST/m/base.apk" AndroidManifest.xml > "$ST/badmanifest.xml"

# variant NAME: writes $ST/NAME.apk from $APK (signature files dropped), changed as NAME says.
variant() {
  python3 - "$APK" "$ST/$1.unsigned.apk" "$1" "$ST" <<'EOF'
import struct, sys, zipfile
src, dst, kind, st = sys.argv[1:5]
def data_of(name):
    return open(f"{st}/{name}", "rb").read()
with zipfile.ZipFile(src) as zin, zipfile.ZipFile(dst, "w") as zout:
    entries = [(i, zin.read(i)) for i in zin.infolist()
               if not (i.filename.startswith("META-INF/") and i.filename.split(".")[-1] in ("SF", "RSA", "EC", "DSA", "MF"))]
    if kind == "missing-abi":
        entries = [e for e in entries if not e[0].filename.startswith("lib/armeabi-v7a/")]
    if kind == "wrong-abi":
        arm = [d for i, d in entries if i.filename == "lib/arm64-v8a/libecvo_jni.so"][0]
        entries = [(i, arm if i.filename == "lib/x86_64/libecvo_jni.so" else d) for i, d in entries]
    if kind == "manifest-class":
        entries = [(i, data_of("plain.dex") if i.filename == "classes.dex" else d) for i, d in entries]
    if kind == "badging":
        entries = [(i, data_of("badmanifest.xml") if i.filename == "AndroidManifest.xml" else d) for i, d in entries]
    for info, data in entries:
        new = zipfile.ZipInfo(info.filename, info.date_time)
        new.compress_type = info.compress_type
        is_so = info.filename.endswith(".so")
        if kind == "so-compressed" and info.filename == "lib/x86_64/libecvo_jni.so":
            new.compress_type = zipfile.ZIP_DEFLATED
        if new.compress_type == zipfile.ZIP_STORED:
            align = 16384 if is_so else 4
            if kind == "so-misaligned" and is_so:
                align = 4  # 4-byte aligned, then pushed off every 16 KB boundary
            start = zout.fp.tell() + 30 + len(info.filename.encode())
            pad = (-(start + 4)) % align
            if kind == "so-misaligned" and is_so and (start + 4 + pad) % 16384 == 0:
                pad += 4
            new.extra = struct.pack("<HH", 0xD935, pad) + b"\0" * pad
        zout.writestr(new, data)
    if kind == "invoke-custom":
        zout.writestr("classes2.dex", data_of("lambda.dex"))
EOF
  if [ "$1" = unsigned ]; then cp "$ST/$1.unsigned.apk" "$ST/$1.apk"; return; fi
  apksigner sign --ks "$ST/k.jks" --ks-pass pass:selftest --key-pass pass:selftest --ks-key-alias k \
    --min-sdk-version 26 --out "$ST/$1.apk" "$ST/$1.unsigned.apk" || die "apksigner sign ($1)"
}

# name -> the checks it must fail (space-separated, sorted); "" = must pass.
declare -A EXPECT=(
  [intact]=""
  [unsigned]="signature"
  [so-compressed]="libs"
  [so-misaligned]="libs"
  [missing-abi]="libs"
  [wrong-abi]="libs"
  [invoke-custom]="dex"
  [manifest-class]="manifest"
  [badging]="badging"
)
passed=0; failed=0
for v in intact unsigned so-compressed so-misaligned missing-abi wrong-abi invoke-custom manifest-class badging; do
  variant "$v"
  out="$(check_apk "$ST/$v.apk" || true)"
  got="$( { grep -o '^FAIL\[[a-z]*\]' <<<"$out" || true; } | sed 's/FAIL\[//;s/\]//' | sort -u | tr '\n' ' ' | sed 's/ $//')"
  if [ "$got" = "${EXPECT[$v]}" ]; then
    passed=$((passed + 1)); log "selftest $v: ok (fails: ${got:-none}) $(grep "^FAIL" <<<"$out" | head -2 | tr "\n" " ")"
  else
    failed=$((failed + 1)); log "selftest $v: WRONG: expected fails '${EXPECT[$v]}', got '${got}'"; echo "$out" >&2
  fi
done
echo "check-apk selftest: $passed passed, $failed failed"
[ $failed = 0 ] || die "check-apk.sh self-test failed"
