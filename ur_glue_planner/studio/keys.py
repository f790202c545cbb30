"""Seed 1's keys in the page: where they go, said on the page, and arrow keys that turn only the tool.

Two things got in a user's way. viser's page turns its camera while an arrow key is held (its keyboard camera
listens on ``document``), so one tap turned the view as well as the tool. And after typing in a field (the
Waypoint number), Up stepped that number (selecting the next waypoint) and C and N did nothing until the 3D view
was clicked, with nothing on the page saying so.

viser has no server-side switch for either, so the page gets a small script (``KEYS_HTML``, added with
``gui.add_html``; viser sets that HTML with innerHTML, where a ``<script>`` does not run but an ``onerror``
handler does). It:

- stops arrow keys at ``<html>``, after the command hotkeys (which listen there) and before the camera;
- hands the keys back to the tool when Enter or Esc is pressed in a field;
- makes C and N act from a number field (which cannot take letters anyway);
- shows in a line of fixed height where the keys go now.
"""
from __future__ import annotations

import html

TOOL_TEXT = 'Keys turn the tool of the selected waypoint: Up/Down, Left/Right; C saves, N goes to the next.'

KEY_SCRIPT = r"""
(function () {
  if (window.__studioKeys) return;
  window.__studioKeys = true;
  var ARROWS = ['ArrowUp', 'ArrowDown', 'ArrowLeft', 'ArrowRight'];
  var LETTERS = ['c', 'n'];
  function isField(el) {
    return !!el && (el.tagName === 'INPUT' || el.tagName === 'TEXTAREA' || el.tagName === 'SELECT' ||
                    el.isContentEditable);
  }
  function isNumber(el) {
    return isField(el) && el.tagName === 'INPUT' && (el.inputMode === 'decimal' || el.inputMode === 'numeric');
  }
  function labelOf(el) {
    var label = el.id ? document.querySelector('label[for="' + CSS.escape(el.id) + '"]') : null;
    return label ? label.textContent.trim() : 'a field';
  }
  function show() {
    var box = document.getElementById('studio-keys');
    if (!box) return;
    var el = document.activeElement;
    var text = TOOL_TEXT, target = 'tool';
    if (isField(el) && isNumber(el)) {
      target = 'field';
      text = 'Keys go to the field \u201c' + labelOf(el) + '\u201d: Up/Down change its number. ' +
             'Enter or Esc gives them back to the tool (C and N work anyway).';
    } else if (isField(el)) {
      target = 'field';
      text = 'Keys type into \u201c' + labelOf(el) + '\u201d. Enter or Esc gives them back to the tool.';
    }
    box.textContent = text;
    box.setAttribute('data-target', target);
  }
  document.documentElement.addEventListener('keydown', function (e) {
    if (ARROWS.indexOf(e.key) >= 0 && !isField(e.target)) e.stopPropagation();
  });
  document.addEventListener('keydown', function (e) {
    var el = e.target;
    if (!isField(el)) return;
    if (e.key === 'Enter' || e.key === 'Escape') {
      setTimeout(function () { el.blur(); }, 0);  // after the field has taken the key
    } else if (isNumber(el) && LETTERS.indexOf(e.key.toLowerCase()) >= 0 && !e.ctrlKey && !e.metaKey &&
               !e.altKey) {
      e.preventDefault();
      el.blur();
      document.body.dispatchEvent(new KeyboardEvent('keydown', {key: e.key, code: e.code, bubbles: true}));
    }
  }, true);
  document.addEventListener('focusin', show);
  document.addEventListener('focusout', function () { setTimeout(show, 0); });
  show();
})();
""".replace('TOOL_TEXT', repr(TOOL_TEXT))

# The indicator (two lines of fixed height) and the script, run once by the image's onerror.
KEYS_HTML = (f'<div id="studio-keys" data-target="tool" style="height:2.7em;overflow:hidden;line-height:1.35em;'
             f'font-size:0.85em;color:#555">{html.escape(TOOL_TEXT)}</div>'
             f'<img alt="" src="data:," style="display:none" onerror="{html.escape(KEY_SCRIPT, quote=True)}">')
