from glob import glob

from setuptools import setup

PACKAGE = "bearing_bringup"

setup(
    name=PACKAGE,
    version="0.1.0",
    packages=[PACKAGE],
    data_files=[
        ("share/ament_index/resource_index/packages", ["resource/" + PACKAGE]),
        ("share/" + PACKAGE, ["package.xml"]),
        ("share/" + PACKAGE + "/launch", glob("launch/*.launch.py")),
        ("share/" + PACKAGE + "/config", glob("config/*.yaml") + glob("config/*.json")),
    ],
    install_requires=["setuptools"],
    zip_safe=False,
    maintainer="bearing-monitor maintainers",
    maintainer_email="maintainers@bearing-monitor.invalid",
    description="Launch file, parameters, the bearing-graph starter and bearing-bag tools.",
    license="Apache-2.0",
    entry_points={
        "console_scripts": [
            "bearing-graph = bearing_bringup.graph_cli:main",
            "nodes = bearing_bringup.executables:nodes",
        ],
    },
)
