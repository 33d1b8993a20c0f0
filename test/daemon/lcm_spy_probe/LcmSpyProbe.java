// A Java agent for the lcm-spy test (test/daemon/run_lcm_spy_test.sh): loaded into the
// lcm-spy JVM through JDK_JAVA_OPTIONS=-javaagent:lcm_spy_probe.jar, it reads back what
// lcm-spy shows, without OCR:
//
//  * the channel table exactly as drawn: the text of every cell's renderer (the JLabel that
//    Swing paints), read on the event thread from the JTable in the "LCM Spy" window;
//  * the object lcm-spy decoded last on each channel (ChannelData.last, the object its
//    viewer shows), as the set of classes in its object tree, e.g. stereo_pair_t holds
//    image_t, camera_calibration_t and pose_t objects;
//  * a screenshot of the window (java.awt.Robot: the pixels of the X display) as a PNG,
//    optionally with lcm-spy's viewer of one channel opened beside it.
//
// It writes nothing to lcm-spy's own output and does not touch its behaviour. Settings come
// from the environment:
//   CBLOX_SPY_PROBE_READY     file created once the LCM Spy window is showing
//   CBLOX_SPY_PROBE_CHANNELS  comma-separated channels to wait for
//   CBLOX_SPY_PROBE_MIN_MSGS  messages each must have ("Num Msgs"), default 2
//   CBLOX_SPY_PROBE_TIMEOUT_S give up waiting after this many seconds, default 30
//   CBLOX_SPY_PROBE_TABLE     output: the table, tab-separated, header line first
//   CBLOX_SPY_PROBE_DECODED   output: "CHANNEL<TAB>class of ChannelData.cls<TAB>classes in
//                             the decoded object tree (comma-separated, sorted)"
//   CBLOX_SPY_PROBE_PNG       output: the screenshot
//   CBLOX_SPY_PROBE_OPEN      a channel whose viewer (the decoded fields of its last
//                             message) to open, by double-clicking its row, before the
//                             screenshot; it is placed right of the table
// The table written is the one read once every channel has its messages and the bus has been
// quiet for 1.5 s, before the viewer opens (see step 2b). The table file is written last
// (atomically): its presence means the probe is done. When
// waiting times out the probe still writes everything it has, so the test shows what was
// missing.
import java.awt.Component;
import java.awt.Container;
import java.awt.Frame;
import java.awt.Point;
import java.awt.Rectangle;
import java.awt.Robot;
import java.awt.Toolkit;
import java.awt.Window;
import java.awt.event.InputEvent;
import java.awt.image.BufferedImage;
import java.io.File;
import java.io.IOException;
import java.lang.instrument.Instrumentation;
import java.lang.reflect.Array;
import java.lang.reflect.Field;
import java.lang.reflect.Modifier;
import java.nio.charset.StandardCharsets;
import java.nio.file.Files;
import java.nio.file.Path;
import java.nio.file.StandardCopyOption;
import java.util.ArrayList;
import java.util.IdentityHashMap;
import java.util.List;
import java.util.Map;
import java.util.TreeSet;
import javax.imageio.ImageIO;
import javax.swing.JLabel;
import javax.swing.JTable;
import javax.swing.SwingUtilities;
import javax.swing.table.TableModel;

public final class LcmSpyProbe {
  private LcmSpyProbe() {}

  public static void premain(String args, Instrumentation inst) {
    Thread t = new Thread(LcmSpyProbe::run, "cblox-lcm-spy-probe");
    t.setDaemon(true);
    t.start();
  }

  private static String env(String name, String fallback) {
    String v = System.getenv(name);
    return v == null || v.isEmpty() ? fallback : v;
  }

  private static void log(String msg) {
    System.err.println("lcm_spy_probe: " + msg);
  }

  private static void run() {
    try {
      probe();
    } catch (Throwable e) {
      log("failed: " + e);
      e.printStackTrace();
    }
  }

  private static void probe() throws Exception {
    final List<String> channels = new ArrayList<>();
    for (String c : env("CBLOX_SPY_PROBE_CHANNELS", "").split(",")) {
      if (!c.isEmpty()) channels.add(c);
    }
    final long minMsgs = Long.parseLong(env("CBLOX_SPY_PROBE_MIN_MSGS", "2"));
    final long deadline =
        System.nanoTime() + (long) (Double.parseDouble(env("CBLOX_SPY_PROBE_TIMEOUT_S", "30")) * 1e9);
    final String readyPath = env("CBLOX_SPY_PROBE_READY", "");
    final String tablePath = env("CBLOX_SPY_PROBE_TABLE", "");
    final String decodedPath = env("CBLOX_SPY_PROBE_DECODED", "");
    final String pngPath = env("CBLOX_SPY_PROBE_PNG", "");
    final String openChannel = env("CBLOX_SPY_PROBE_OPEN", "");

    // 1. The LCM Spy window and its channel table.
    Frame frame = null;
    JTable table = null;
    while (System.nanoTime() < deadline) {
      for (Window w : Window.getWindows()) {
        if (w instanceof Frame && "LCM Spy".equals(((Frame) w).getTitle()) && w.isShowing()) {
          frame = (Frame) w;
          table = findTable(frame);
        }
      }
      if (table != null) break;
      Thread.sleep(100);
    }
    if (table == null) {
      log("no showing \"LCM Spy\" window with a table before the timeout");
      return;
    }
    if (!readyPath.isEmpty()) Files.writeString(Path.of(readyPath), "ready\n");
    log("window showing; waiting for " + channels.size() + " channels");

    // 2. Wait until every expected channel has at least minMsgs messages in the table.
    List<List<String>> rows = readTable(table);
    while (System.nanoTime() < deadline && !allSeen(rows, channels, minMsgs)) {
      Thread.sleep(200);
      rows = readTable(table);
    }
    if (!allSeen(rows, channels, minMsgs)) log("timed out waiting for the channels");

    // 2b. Wait until the publisher has finished (no count changes for 1.5 s). These are the
    //     counts the test checks: they are read before any viewer opens, because lcm-spy's
    //     Spy.createViewer publishes cd.viewer before calling its setViewport, and a message
    //     arriving in between makes ObjectPanel.setObject throw a NullPointerException that
    //     lcm-spy counts as undecodable (seen once in CI on CBLOX_STEREO). A viewer opened
    //     on a quiet bus shows the last message (createViewer passes cd.last).
    long quietSince = System.nanoTime();
    while (System.nanoTime() < deadline && System.nanoTime() - quietSince < 1_500_000_000L) {
      Thread.sleep(250);
      List<List<String>> now = readTable(table);
      if (!counts(now).equals(counts(rows))) quietSince = System.nanoTime();
      rows = now;
    }
    if (System.nanoTime() - quietSince < 1_500_000_000L) log("the bus did not go quiet");
    final List<List<String>> checked = rows;

    // 3. Optionally open lcm-spy's viewer of one channel as a user does (a double click on
    //    its row, through the X server) and place it right of the table.
    Frame viewer = openChannel.isEmpty() ? null : openViewer(frame, table, openChannel);

    // 4. Let the rate thread refresh the table (once a second) and Swing repaint, then
    //    screenshot exactly what is on the display and read the table once more.
    Thread.sleep(1300);
    final Frame f = frame;
    SwingUtilities.invokeAndWait(() -> { f.repaint(); if (viewer != null) viewer.repaint(); });
    SwingUtilities.invokeAndWait(() -> {});
    Toolkit.getDefaultToolkit().sync();
    rows = readTable(table);  // right before the screenshot
    if (!counts(rows).equals(counts(checked))) {
      log("the counts changed after the checked table was read: " + counts(checked) + " -> " +
          counts(rows));
    }
    if (!pngPath.isEmpty()) {
      try {
        Rectangle r = new Rectangle(frame.getLocationOnScreen(), frame.getSize());
        if (viewer != null) r = r.union(new Rectangle(viewer.getLocationOnScreen(), viewer.getSize()));
        r = r.intersection(new Rectangle(Toolkit.getDefaultToolkit().getScreenSize()));
        BufferedImage img = new Robot().createScreenCapture(r);
        File tmp = new File(pngPath + ".tmp");
        ImageIO.write(img, "png", tmp);
        Files.move(tmp.toPath(), Path.of(pngPath), StandardCopyOption.REPLACE_EXISTING);
        log("screenshot " + r.width + "x" + r.height + " written to " + pngPath);
      } catch (Exception e) {
        log("screenshot failed: " + e);
      }
    }

    if (!decodedPath.isEmpty()) writeAtomically(decodedPath, decodedObjects(table));
    StringBuilder out = new StringBuilder();
    for (List<String> row : checked) out.append(String.join("\t", row)).append('\n');
    if (!tablePath.isEmpty()) writeAtomically(tablePath, out.toString());
    log("table of " + (rows.size() - 1) + " channels written");
  }

  /** The "Num Msgs" and "Undecodable" cells of every row (all cells when absent). */
  private static List<String> counts(List<List<String>> rows) {
    List<String> out = new ArrayList<>();
    if (rows.isEmpty()) return out;
    List<String> header = rows.get(0);
    int msgs = header.indexOf("Num Msgs"), undecodable = header.indexOf("Undecodable");
    for (List<String> row : rows.subList(1, rows.size())) {
      if (msgs < 0 || undecodable < 0 || row.size() <= Math.max(msgs, undecodable)) {
        out.add(String.join("|", row));
      } else {
        out.add(row.get(0) + ":" + row.get(msgs) + "/" + row.get(undecodable));
      }
    }
    return out;
  }

  /** Double-clicks the row of `channel` with java.awt.Robot; returns the viewer window. */
  private static Frame openViewer(Frame main, JTable table, String channel) throws Exception {
    final Point[] at = {null};
    SwingUtilities.invokeAndWait(() -> {
      int col = table.getColumnModel().getColumnIndex("Channel");
      for (int r = 0; r < table.getRowCount(); ++r) {
        if (channel.equals(String.valueOf(table.getValueAt(r, col)))) {
          Rectangle cell = table.getCellRect(r, col, true);
          Point p = table.getLocationOnScreen();
          at[0] = new Point(p.x + cell.x + cell.width / 2, p.y + cell.y + cell.height / 2);
        }
      }
    });
    if (at[0] == null) {
      log("no row " + channel + " to open");
      return null;
    }
    Robot robot = new Robot();
    robot.setAutoDelay(40);
    robot.mouseMove(at[0].x, at[0].y);
    for (int i = 0; i < 2; ++i) {
      robot.mousePress(InputEvent.BUTTON1_DOWN_MASK);
      robot.mouseRelease(InputEvent.BUTTON1_DOWN_MASK);
    }
    robot.waitForIdle();
    for (int i = 0; i < 50; ++i) {
      for (Window w : Window.getWindows()) {
        if (w instanceof Frame && channel.equals(((Frame) w).getTitle()) && w.isShowing()) {
          final Frame v = (Frame) w;
          SwingUtilities.invokeAndWait(() -> v.setBounds(main.getX() + main.getWidth(), main.getY(),
                                                         v.getWidth(), main.getHeight()));
          Thread.sleep(300);
          log("viewer of " + channel + " open");
          return v;
        }
      }
      Thread.sleep(100);
    }
    log("the viewer of " + channel + " did not open");
    return null;
  }

  private static JTable findTable(Container c) {
    for (Component child : c.getComponents()) {
      if (child instanceof JTable) return (JTable) child;
      if (child instanceof Container) {
        JTable t = findTable((Container) child);
        if (t != null) return t;
      }
    }
    return null;
  }

  /** Header line, then one line per view row: the text each cell renderer paints. */
  private static List<List<String>> readTable(JTable table) throws Exception {
    final List<List<String>> rows = new ArrayList<>();
    SwingUtilities.invokeAndWait(() -> {
      List<String> header = new ArrayList<>();
      for (int c = 0; c < table.getColumnCount(); ++c) header.add(clean(table.getColumnName(c)));
      rows.add(header);
      for (int r = 0; r < table.getRowCount(); ++r) {
        List<String> row = new ArrayList<>();
        for (int c = 0; c < table.getColumnCount(); ++c) {
          Component comp = table.prepareRenderer(table.getCellRenderer(r, c), r, c);
          String text = comp instanceof JLabel ? ((JLabel) comp).getText()
                                               : String.valueOf(table.getValueAt(r, c));
          row.add(clean(text));
        }
        rows.add(row);
      }
    });
    return rows;
  }

  private static String clean(String s) {
    return s == null ? "" : s.replace('\t', ' ').replace('\n', ' ').trim();
  }

  private static boolean allSeen(List<List<String>> rows, List<String> channels, long minMsgs) {
    List<String> header = rows.get(0);
    int chCol = header.indexOf("Channel");
    int numCol = header.indexOf("Num Msgs");
    if (chCol < 0 || numCol < 0) return false;
    for (String ch : channels) {
      boolean ok = false;
      for (List<String> row : rows.subList(1, rows.size())) {
        if (row.get(chCol).equals(ch)) {
          try {
            ok = Long.parseLong(row.get(numCol)) >= minMsgs;
          } catch (NumberFormatException e) {
            ok = false;
          }
        }
      }
      if (!ok) return false;
    }
    return true;
  }

  /**
   * The objects lcm-spy decoded: the table's model is lcm.util.TableSorter over
   * Spy$ChannelTableModel, whose Spy holds channelMap (channel -> lcm.spy.ChannelData with
   * the public fields cls and last). These are lcm-spy internals (lcm 1.3 to 1.5); if they
   * change, the file says so on every line and the test fails with that message.
   */
  private static String decodedObjects(JTable table) {
    StringBuilder out = new StringBuilder();
    try {
      TableModel sorter = table.getModel();
      Object inner = field(sorter, "tableModel");
      Object spy = field(inner, "this$0");
      Map<?, ?> channelMap = (Map<?, ?>) field(spy, "channelMap");
      synchronized (field(spy, "channelList")) {
        for (Object channel : new TreeSet<Object>(channelMap.keySet())) {
          Object cd = channelMap.get(channel);
          Class<?> cls = (Class<?>) cd.getClass().getField("cls").get(cd);
          Object last = cd.getClass().getField("last").get(cd);
          TreeSet<String> classes = new TreeSet<>();
          collectClasses(last, classes, new IdentityHashMap<>());
          out.append(channel).append('\t').append(cls == null ? "null" : cls.getName())
              .append('\t').append(String.join(",", classes)).append('\n');
        }
      }
    } catch (ReflectiveOperationException | RuntimeException e) {
      out.append("ERROR\tcannot read lcm-spy's decoded objects: ").append(e).append('\n');
    }
    return out.toString();
  }

  private static Object field(Object o, String name) throws ReflectiveOperationException {
    for (Class<?> c = o.getClass(); c != null; c = c.getSuperclass()) {
      try {
        Field f = c.getDeclaredField(name);
        f.setAccessible(true);
        return f.get(o);
      } catch (NoSuchFieldException e) {
        // look in the superclass
      }
    }
    throw new NoSuchFieldException(o.getClass().getName() + "." + name);
  }

  /** Names of the LCM classes (those with an LCM_FINGERPRINT) in an object tree. */
  private static void collectClasses(Object o, TreeSet<String> out, IdentityHashMap<Object, Boolean> seen)
      throws IllegalAccessException {
    if (o == null || seen.put(o, Boolean.TRUE) != null) return;
    Class<?> c = o.getClass();
    if (c.isArray()) {
      if (c.getComponentType().isPrimitive()) return;
      for (int i = 0; i < Array.getLength(o); ++i) collectClasses(Array.get(o, i), out, seen);
      return;
    }
    boolean isLcm;
    try {
      Field fp = c.getField("LCM_FINGERPRINT");
      isLcm = Modifier.isStatic(fp.getModifiers());
    } catch (NoSuchFieldException e) {
      isLcm = false;
    }
    if (!isLcm) return;
    out.add(c.getName());
    for (Field f : c.getFields()) {
      if (Modifier.isStatic(f.getModifiers()) || f.getType().isPrimitive()) continue;
      collectClasses(f.get(o), out, seen);
    }
  }

  private static void writeAtomically(String path, String text) throws IOException {
    Path tmp = Path.of(path + ".tmp");
    Files.writeString(tmp, text, StandardCharsets.UTF_8);
    Files.move(tmp, Path.of(path), StandardCopyOption.REPLACE_EXISTING,
        StandardCopyOption.ATOMIC_MOVE);
  }
}
