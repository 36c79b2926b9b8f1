//! The live page itself: one HTML file with its script, which listens to
//! `/events` and swaps in `/image.png` when a new image is announced.

/// The page. The image is swapped only when a new one is complete, so the
/// page never shows a blank or half-loaded frame.
pub(super) const PAGE: &str = r#"<!doctype html>
<html lang="en">
<head>
<meta charset="utf-8">
<title>penumbra watch</title>
<style>
  body { margin: 0; background: #111; color: #ddd; font: 14px/1.4 system-ui, sans-serif; }
  #view { position: relative; display: inline-block; }
  #image { display: block; max-width: 100vw; image-rendering: pixelated; }
  #error { position: absolute; left: 0; right: 0; top: 0; margin: 0; padding: 12px;
           background: rgba(110, 0, 0, 0.85); color: #fff; white-space: pre-wrap;
           font: 13px/1.35 ui-monospace, monospace; }
  #line { padding: 6px 10px; font: 12px/1.4 ui-monospace, monospace; color: #aaa; }
  #status { padding: 6px 10px; color: #888; }
</style>
</head>
<body>
<div id="view">
  <img id="image" alt="latest render">
  <pre id="error" hidden></pre>
</div>
<div id="line"></div>
<div id="status">connecting…</div>
<script>
  const image = document.getElementById('image');
  const error = document.getElementById('error');
  const line = document.getElementById('line');
  const status = document.getElementById('status');
  let shown = 0;
  const events = new EventSource('/events');
  events.addEventListener('open', () => { status.textContent = 'live'; });
  events.addEventListener('error', () => { status.textContent = 'disconnected; reconnecting…'; });
  events.addEventListener('frame', (e) => {
    const d = JSON.parse(e.data);
    if (d.version > 0 && d.version !== shown) {
      const next = new Image();
      // Loads can finish out of order: never go back to an older image.
      next.onload = () => {
        if (d.version > Number(image.dataset.version || 0)) {
          image.src = next.src;
          image.dataset.version = d.version;
        }
      };
      next.src = '/image.png?v=' + d.version;
      shown = d.version;
    }
    error.textContent = d.error || '';
    error.hidden = !d.error;
    line.textContent = d.line;
  });
</script>
</body>
</html>
"#;

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_page_listens_and_does_not_poll() {
        assert!(PAGE.contains("new EventSource('/events')"));
        assert!(!PAGE.contains("setInterval") && !PAGE.contains("setTimeout"));
    }
}
