"""The studio's browser pages (NiceGUI): one module per view, laying out the logic of
:mod:`jvl_gym.studio`; :mod:`.app` builds them and runs the server."""
