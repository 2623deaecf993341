#!/bin/sh
# Gradle wrapper launcher for ecvo (POSIX sh). It runs the wrapper jar, which downloads the
# Gradle of gradle/wrapper/gradle-wrapper.properties on first use. The jar itself is not
# committed (it cannot be fetched on the machines that develop ecvo); create it once with any
# installed Gradle:  gradle wrapper --gradle-version 8.14.3 --distribution-type bin
# (that also rewrites this script with Gradle's own, which is equivalent).
APP_HOME=$(cd "$(dirname "$0")" && pwd -P) || exit
JAR="$APP_HOME/gradle/wrapper/gradle-wrapper.jar"
if [ ! -f "$JAR" ]; then
    echo "gradlew: $JAR is missing. Run once, with any Gradle installed:" >&2
    echo "    gradle wrapper --gradle-version 8.14.3 --distribution-type bin" >&2
    exit 1
fi
if [ -n "$JAVA_HOME" ]; then
    JAVACMD="$JAVA_HOME/bin/java"
else
    JAVACMD=java
fi
command -v "$JAVACMD" >/dev/null 2>&1 || { echo "gradlew: no java (set JAVA_HOME to a JDK 17)" >&2; exit 1; }
# shellcheck disable=SC2086
exec "$JAVACMD" -Xmx64m -Xms64m $JAVA_OPTS $GRADLE_OPTS "-Dorg.gradle.appname=gradlew" \
    -classpath "$JAR" org.gradle.wrapper.GradleWrapperMain "$@"
