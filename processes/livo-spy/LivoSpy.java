// lcm-spy for the suite (scripts/livo-spy runs it): starts Debian's lcm.spy.Spy unchanged, then gives
// its UDP multicast socket the receive buffer the URL asks for.
//
// Why this is needed: LCM's Java provider (lcm.lcm.UDPMulticastProvider, LCM 1.3.1) honours only the
// `ttl` (and network) of a udpm:// URL. It never sets SO_RCVBUF, so its socket keeps the kernel's
// default (net.core.rmem_default, 208 KiB on Debian). A message larger than 64 kB arrives as a burst of
// 64 kB fragments that the sender pushes through the loopback device faster than the one reader thread
// drains it (the same thread also decodes every message for the table); once the buffer is full the
// rest of the burst is dropped, and a message with one fragment missing is never delivered. LIVO_LIDAR
// (~530 kB, 9 fragments), LIVO_FRAME (~0.9 MB) and LIVO_SUBMAP (up to 11 MB) therefore never appeared,
// while the images (~330 kB) mostly did. The C provider reads `recv_buf_size` from the URL; this
// launcher does the same for the Java one (reflection on the provider's socket).
//
// Options (besides lcm-spy's own --lcm-url):
//   --print-table S    every S seconds print lcm-spy's channel table (read from its window) on stdout
//   --screenshot FILE  with --print-table: also write the window as PNG each time
//   --quit-after S     exit after S seconds (for scripts and tests)
package livo.spy;

import java.awt.Frame;
import java.awt.Graphics2D;
import java.awt.image.BufferedImage;
import java.io.BufferedReader;
import java.io.File;
import java.io.IOException;
import java.lang.reflect.Field;
import java.net.MulticastSocket;
import java.nio.file.Files;
import java.nio.file.Paths;
import java.util.List;
import java.util.Map;
import java.util.concurrent.ConcurrentHashMap;
import javax.imageio.ImageIO;
import javax.swing.JFrame;
import javax.swing.JTable;
import javax.swing.SwingUtilities;

public final class LivoSpy {
  private static final String DEFAULT_URL = "udpm://239.255.76.67:7667?ttl=0&recv_buf_size=4194304";

  private LivoSpy() {}

  private static void usage(int code) {
    System.err.println("usage: livo-spy [--lcm-url URL] [--print-table S] [--screenshot FILE] [--quit-after S]");
    System.err.println("  lcm-spy with the receive buffer of the URL's recv_buf_size (LCM's Java provider ignores it)");
    System.err.println("  --print-table S    print lcm-spy's channel table on stdout every S seconds");
    System.err.println("  --screenshot FILE  with --print-table: also write the window as PNG each time");
    System.err.println("  --quit-after S     exit after S seconds");
    System.exit(code);
  }

  /** The value of `key` in the URL's query ("udpm://a:p?ttl=0&recv_buf_size=N"), or null. */
  static String urlParameter(String url, String key) {
    final int q = url.indexOf('?');
    if (q < 0) return null;
    for (String kv : url.substring(q + 1).split("&")) {
      final int eq = kv.indexOf('=');
      if (eq > 0 && kv.substring(0, eq).equals(key)) return kv.substring(eq + 1);
    }
    return null;
  }

  static Object field(Object o, String name) throws ReflectiveOperationException {
    for (Class<?> c = o.getClass(); c != null; c = c.getSuperclass()) {
      try {
        Field f = c.getDeclaredField(name);
        f.setAccessible(true);
        return f.get(o);
      } catch (NoSuchFieldException e) {
        // try the superclass
      }
    }
    throw new NoSuchFieldException(o.getClass().getName() + "." + name);
  }

  /** The number in a /proc file (a line read: Files.readAllBytes returns a truncated /proc file). */
  static long readLong(String path) {
    try (BufferedReader r = Files.newBufferedReader(Paths.get(path))) {
      final String line = r.readLine();
      return line == null ? -1 : Long.parseLong(line.trim());
    } catch (IOException | NumberFormatException e) {
      return -1;
    }
  }

  /** Gives every UDP multicast socket of the Spy's LCM object `bytes` of receive buffer; prints what the kernel granted. */
  static void raiseReceiveBuffer(Object spy, int bytes) throws ReflectiveOperationException, IOException {
    final Object lcm = field(spy, "lcm");
    final List<?> providers = (List<?>) field(lcm, "providers");
    final long rmemMax = readLong("/proc/sys/net/core/rmem_max");
    for (Object p : providers) {
      if (!p.getClass().getName().equals("lcm.lcm.UDPMulticastProvider")) continue;
      final MulticastSocket sock = (MulticastSocket) field(p, "sock");
      final int before = sock.getReceiveBufferSize();
      sock.setReceiveBufferSize(bytes);
      final int got = sock.getReceiveBufferSize();
      // As Java reports it (Linux doubles the value for its bookkeeping, Java halves it back); capped by the
      // kernel at net.core.rmem_max.
      System.err.printf("livo-spy: receive buffer %d -> %d bytes (recv_buf_size=%d; net.core.rmem_max=%d)%n", before,
                        got, bytes, rmemMax);
      if (got < bytes) {
        System.err.printf("livo-spy: the kernel capped the buffer at net.core.rmem_max=%d: bursts larger than about"
                              + " %d kB get lost; raise it: sudo sysctl -w net.core.rmem_max=%d%n",
                          rmemMax, got / 1000, bytes);
      }
    }
  }

  /** Largest message seen per channel (the table has rates, not sizes). */
  static final Map<String, Integer> largest = new ConcurrentHashMap<>();

  /** lcm-spy's channel table, as shown (sorted by channel), tab-separated with a header, plus the largest message. */
  static String table(JTable t) {
    final StringBuilder sb = new StringBuilder();
    for (int c = 0; c < t.getColumnCount(); ++c) sb.append(c > 0 ? "\t" : "").append(t.getColumnName(c));
    sb.append("\tLargest\n");
    for (int r = 0; r < t.getRowCount(); ++r) {
      String channel = "";
      for (int c = 0; c < t.getColumnCount(); ++c) {
        final Object v = t.getValueAt(r, c);
        final String s = v == null ? "" : v.toString().trim();
        if (c == 0) channel = s;
        sb.append(c > 0 ? "\t" : "").append(s);
      }
      final Integer size = largest.get(channel);
      sb.append("\t").append(size == null ? "-" : String.format("%.1f kB", size / 1000.0)).append("\n");
    }
    return sb.toString();
  }

  static void screenshot(String path) throws IOException {
    for (Frame f : Frame.getFrames()) {
      if (!(f instanceof JFrame) || !f.isShowing() || !"LCM Spy".equals(f.getTitle())) continue;
      final JFrame frame = (JFrame) f;
      final BufferedImage img = new BufferedImage(frame.getRootPane().getWidth(), frame.getRootPane().getHeight(),
                                                  BufferedImage.TYPE_INT_RGB);
      final Graphics2D g = img.createGraphics();
      frame.getRootPane().printAll(g);
      g.dispose();
      ImageIO.write(img, "png", new File(path));
      return;
    }
  }

  public static void main(String[] args) throws Exception {
    String url = System.getenv("LCM_DEFAULT_URL");
    if (url == null || url.isEmpty()) url = DEFAULT_URL;
    double printEvery = 0, quitAfter = 0;
    String shot = null;
    for (int i = 0; i < args.length; ++i) {
      final String a = args[i];
      final boolean hasNext = i + 1 < args.length;
      if (a.equals("-h") || a.equals("--help")) usage(0);
      else if (a.startsWith("--lcm-url=")) url = a.substring(10);
      else if ((a.equals("--lcm-url") || a.equals("-l")) && hasNext) url = args[++i];
      else if (a.equals("--print-table") && hasNext) printEvery = Double.parseDouble(args[++i]);
      else if (a.equals("--screenshot") && hasNext) shot = args[++i];
      else if (a.equals("--quit-after") && hasNext) quitAfter = Double.parseDouble(args[++i]);
      else {
        System.err.println("livo-spy: unknown or incomplete option '" + a + "'");
        usage(2);
      }
    }
    System.err.println("livo-spy: " + url);
    final Object spy = new lcm.spy.Spy(url);
    final String rb = urlParameter(url, "recv_buf_size");
    if (url.startsWith("udpm://")) {
      if (rb != null) raiseReceiveBuffer(spy, Integer.parseInt(rb));
      else System.err.println("livo-spy: no recv_buf_size in the URL: the kernel's default buffer loses large messages");
    }
    final lcm.lcm.LCM lcm = (lcm.lcm.LCM) field(spy, "lcm");
    lcm.subscribeAll((l, channel, ins) -> largest.merge(channel, ins.available(), Math::max));
    final JTable channels = (JTable) field(spy, "channelTable");
    final long start = System.nanoTime();
    final String shotPath = shot;
    final double every = printEvery;
    final double quit = quitAfter;
    if (every > 0 || quit > 0) {
      final Thread t = new Thread(() -> {
        try {
          double next = every > 0 ? every : quit;
          while (true) {
            final double now = (System.nanoTime() - start) / 1e9;
            if (now < next) {
              Thread.sleep((long) Math.ceil((next - now) * 1000));
              continue;
            }
            if (every > 0) {
              final String[] text = new String[1];
              SwingUtilities.invokeAndWait(() -> text[0] = table(channels));
              System.out.printf("# lcm-spy channels at %.1f s%n%s%n", now, text[0]);
              System.out.flush();
              if (shotPath != null) {
                SwingUtilities.invokeAndWait(() -> {
                  try {
                    screenshot(shotPath);
                  } catch (IOException e) {
                    System.err.println("livo-spy: " + shotPath + ": " + e.getMessage());
                  }
                });
                System.out.printf("# window written to %s%n%n", shotPath);
                System.out.flush();
              }
            }
            if (quit > 0 && now >= quit) System.exit(0);
            next += every > 0 ? every : quit;
          }
        } catch (Exception e) {
          System.err.println("livo-spy: " + e);
        }
      });
      t.setDaemon(true);
      t.start();
    }
  }
}
