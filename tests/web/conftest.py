def pytest_addoption(parser):
    parser.addoption("--ftctune", default="build/tools/ftctune",
                     help="the ftctune binary whose `serve` the dashboard tests start")
