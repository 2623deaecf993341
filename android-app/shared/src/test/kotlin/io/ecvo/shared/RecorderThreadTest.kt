package io.ecvo.shared

import io.ecvo.PushStatus
import java.io.File
import java.io.IOException
import java.util.Collections
import java.util.concurrent.CountDownLatch
import java.util.concurrent.TimeUnit
import org.junit.Assert.assertEquals
import org.junit.Assert.assertFalse
import org.junit.Assert.assertNull
import org.junit.Assert.assertTrue
import org.junit.Test

/** Recording on its own thread with a bounded queue. */
class RecorderThreadTest {
    /** Blocks in [writeFrame] until [release] opens; keeps what it was given. */
    private class BlockingRecorder(override val dir: File) : FrameRecorder {
        val entered = CountDownLatch(1)
        val release = CountDownLatch(1)
        val written = Collections.synchronizedList(ArrayList<Pair<Long, Short>>())
        var failAt = -1
        @Volatile var closed = false
        override val framesWritten: Int get() = written.size
        override fun writeFrame(timestampNs: Long, depth: ShortArray, intensity: ByteArray) {
            entered.countDown()
            release.await(10, TimeUnit.SECONDS)
            if (written.size == failAt) throw IOException("No space left on device")
            written += timestampNs to depth[0]
        }
        override fun close() { closed = true }
    }

    private val depth = ShortArray(4) { 1000 }
    private val gray = ByteArray(4) { 9 }

    @Test
    fun aFullQueueDropsFramesAndCountsThemWithoutBlockingTheCaller() {
        val fake = BlockingRecorder(File("unused"))
        val r = AsyncRecorder(fake, capacity = 2)
        assertTrue(r.offer(1, depth, gray))
        assertTrue(fake.entered.await(5, TimeUnit.SECONDS)) // the writer holds frame 1
        val t0 = System.nanoTime()
        val taken = (2L..5L).map { r.offer(it, depth, gray) }
        assertTrue("offer blocked", System.nanoTime() - t0 < 1_000_000_000L)
        assertEquals(listOf(true, true, false, false), taken)
        assertEquals(2L, r.framesDropped)
        fake.release.countDown()
        assertTrue(r.finish() === fake)
        assertTrue(fake.closed)
        assertEquals(listOf(1L, 2L, 3L), fake.written.map { it.first })
        assertFalse(r.offer(6, depth, gray)) // finished
        val p = TrackingPresenter().apply { onRecording(true, r.framesDropped) }
        assertTrue(p.status.frames, p.status.frames.contains("2 not recorded"))
    }

    @Test
    fun offerCopiesTheFrameSoTheCallerMayReuseItsArrays() {
        val fake = BlockingRecorder(File("unused"))
        val r = AsyncRecorder(fake)
        val d = ShortArray(4) { 500 }
        r.offer(1, d, gray)
        d[0] = 42
        fake.release.countDown()
        r.finish()
        assertEquals(500.toShort(), fake.written[0].second)
    }

    @Test
    fun aFailedWriteEndsRecordingWithAMessageOnce() {
        val fake = BlockingRecorder(File("/sd/rec")).apply { failAt = 1; release.countDown() }
        val messages = Collections.synchronizedList(ArrayList<String>())
        val r = AsyncRecorder(fake, onFailed = { _, m -> messages += m })
        for (i in 1L..3L) r.offer(i * 10, depth, gray)
        val deadline = System.nanoTime() + 5_000_000_000L
        while (r.failed == null && System.nanoTime() < deadline) Thread.sleep(5)
        Thread.sleep(50)
        assertEquals(1, messages.size)
        assertTrue(messages[0], messages[0].contains("No space left") && messages[0].contains("1 frames"))
        assertTrue(fake.closed)
        assertFalse(r.offer(40, depth, gray))
    }

    @Test
    fun aSessionRecordsOnItsOwnThreadAndShowsDrops() {
        val cam = CameraIntrinsics(8, 8, 10.0, 10.0, 3.5, 3.5)
        val depth = ShortArray(64) { 1000 }
        val gray = ByteArray(64) { 7 }
        val dir = File(TestSupport.tempDir(), "rec")
        val s = TrackingSession(FakeTracker(), recorderCapacity = 64)
        s.startRecording(StreamRecorder(dir, cam))
        for (i in 1..20) assertEquals(PushStatus.ACCEPTED, s.push(i * 33_000_000L, depth, gray))
        assertTrue(s.recording)
        val done = CountDownLatch(1)
        var result: RecordingResult? = null
        var finisher: Thread? = null
        assertTrue(s.stopRecording { r -> result = r; finisher = Thread.currentThread(); done.countDown() })
        assertFalse(s.recording)
        assertTrue(done.await(10, TimeUnit.SECONDS))
        assertTrue("finished on the calling thread", finisher !== Thread.currentThread())
        val res = result!!
        assertEquals(20, res.recorder.framesWritten)
        assertEquals(0L, res.dropped)
        assertNull(res.error)
        assertEquals(0L, s.recordingDropped)
        assertFalse(s.stopRecording()) // nothing left to stop
        assertEquals(20, StreamReader(DirectoryFiles(dir)).frames.size)
        s.close()
    }

    @Test
    fun finishingInTheBackgroundReturnsAtOnceThenReportsTheDropCount() {
        val fake = BlockingRecorder(File("unused"))
        val r = AsyncRecorder(fake, capacity = 2)
        assertTrue(r.offer(1, depth, gray))
        assertTrue(fake.entered.await(5, TimeUnit.SECONDS)) // the writer is stuck in frame 1
        assertEquals(listOf(true, true, false, false), (2L..5L).map { r.offer(it, depth, gray) })
        val done = CountDownLatch(1)
        var doneOn: Thread? = null
        var closedBeforeDone = false
        val t0 = System.nanoTime()
        val finisher = r.finishInBackground { rec, e ->
            assertTrue(rec === fake)
            assertNull(e)
            closedBeforeDone = fake.closed
            doneOn = Thread.currentThread()
            done.countDown()
        }
        // The caller does not wait for the stuck writer.
        assertTrue("finishInBackground blocked", System.nanoTime() - t0 < 500_000_000L)
        assertEquals(1L, done.count)
        assertFalse("frames after the stop are refused", r.offer(6, depth, gray))
        fake.release.countDown()
        assertTrue(done.await(10, TimeUnit.SECONDS))
        assertTrue(doneOn === finisher)
        assertTrue(closedBeforeDone)
        assertEquals(listOf(1L, 2L, 3L), fake.written.map { it.first }) // the queue was drained
        assertEquals(2L, r.framesDropped)
    }
}
