@rem Gradle wrapper launcher for ecvo (Windows). It runs the wrapper jar, which downloads the
@rem Gradle of gradle\wrapper\gradle-wrapper.properties on first use. The jar is not committed;
@rem create it once with any installed Gradle: gradle wrapper --gradle-version 8.14.3 --distribution-type bin
@if "%DEBUG%"=="" @echo off
setlocal
set APP_HOME=%~dp0
set JAR=%APP_HOME%gradle\wrapper\gradle-wrapper.jar
if not exist "%JAR%" (
  echo gradlew: %JAR% is missing. Run once, with any Gradle installed: 1>&2
  echo     gradle wrapper --gradle-version 8.14.3 --distribution-type bin 1>&2
  exit /b 1
)
set JAVACMD=java.exe
if defined JAVA_HOME set JAVACMD=%JAVA_HOME%\bin\java.exe
"%JAVACMD%" -Xmx64m -Xms64m %JAVA_OPTS% %GRADLE_OPTS% "-Dorg.gradle.appname=gradlew" -classpath "%JAR%" org.gradle.wrapper.GradleWrapperMain %*
exit /b %ERRORLEVEL%
