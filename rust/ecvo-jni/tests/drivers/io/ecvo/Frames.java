package io.ecvo;

import java.awt.image.Raster;
import java.io.File;
import java.io.IOException;
import java.nio.ByteBuffer;
import java.nio.ByteOrder;
import java.nio.file.Files;
import java.util.ArrayList;
import java.util.List;
import javax.imageio.ImageIO;

/** The frames of a recorded stream (testdata/synth_phone_320x180), decoded with ImageIO. */
final class Frames {
    final int width, height;
    final double fx, fy, cx, cy;
    final List<short[]> depth = new ArrayList<>();
    final List<byte[]> intensity = new ArrayList<>();
    /** The same frames in direct buffers (little-endian depth), as the app pushes them. */
    final List<ByteBuffer> depthBuffers = new ArrayList<>();
    final List<ByteBuffer> intensityBuffers = new ArrayList<>();

    Frames(File dir) throws IOException {
        String cam = Files.readString(new File(dir, "camera.json").toPath());
        width = (int) num(cam, "width");
        height = (int) num(cam, "height");
        fx = num(cam, "fx"); fy = num(cam, "fy"); cx = num(cam, "cx"); cy = num(cam, "cy");
        List<String> rgb = names(new File(dir, "rgb.txt"));
        List<String> dep = names(new File(dir, "depth.txt"));
        int n = Math.min(rgb.size(), dep.size());
        for (int i = 0; i < n; i++) {
            Raster g = ImageIO.read(new File(dir, rgb.get(i))).getRaster();
            Raster d = ImageIO.read(new File(dir, dep.get(i))).getRaster();
            short[] ds = new short[width * height];
            byte[] gs = new byte[width * height];
            ByteBuffer db = ByteBuffer.allocateDirect(2 * width * height).order(ByteOrder.LITTLE_ENDIAN);
            ByteBuffer gb = ByteBuffer.allocateDirect(width * height);
            for (int y = 0; y < height; y++) {
                for (int x = 0; x < width; x++) {
                    int k = y * width + x;
                    ds[k] = (short) d.getSample(x, y, 0);
                    gs[k] = (byte) g.getSample(x, y, 0);
                    db.putShort(2 * k, ds[k]);
                    gb.put(k, gs[k]);
                }
            }
            depth.add(ds); intensity.add(gs); depthBuffers.add(db); intensityBuffers.add(gb);
        }
    }

    int size() { return depth.size(); }

    /** Frame index of the k-th push: back and forth through the stream, so the motion is continuous. */
    int pingPong(long k) {
        int n = size(), period = 2 * (n - 1);
        int p = (int) (k % period);
        return p < n ? p : period - p;
    }

    private static double num(String json, String key) {
        int i = json.indexOf("\"" + key + "\"");
        int c = json.indexOf(':', i);
        int e = c + 1;
        while (e < json.length() && "0123456789.-+eE ".indexOf(json.charAt(e)) >= 0) e++;
        return Double.parseDouble(json.substring(c + 1, e).trim());
    }

    private static List<String> names(File list) throws IOException {
        List<String> out = new ArrayList<>();
        for (String l : Files.readAllLines(list.toPath())) {
            l = l.trim();
            if (l.isEmpty() || l.startsWith("#")) continue;
            out.add(l.split("\\s+")[1]);
        }
        return out;
    }
}
