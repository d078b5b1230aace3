"""The steps of ``build.py`` (the extension zips), one module each: what is built (``config``),
Blender's extension tooling (``blender_tools``), the wheels (``wheels``), the manifest rewritten
per zip (``manifest``), the zip staged and checked (``zips``). ``build.py`` re-exports their names;
none of this ships in a zip (the manifest's ``[build] paths_exclude_pattern``)."""
