// The ESPRIT extension that runs ncperf inside ESPRIT (Windows only; not compiled on Linux).
//
// ESPRIT loads extensions from its Extensions folder through MEF: a class exported as
// ESPRIT.NetApi.Extensions.IExtension, whose Connect(object app) receives the Application.
// This one adds a ribbon button; a click starts Python through pythonnet's embedding API
// (once), calls adapters.esprit_com.addin.run(app) and shows the summary in the event window.
//
// Build (see ../README.md): a .NET Framework 4.8 x64 class library referencing ESPRIT.NetApi,
// Interop.Esprit and Interop.EspritConstants (ESPRIT's Prog folder, "Copy Local" off) and the
// NuGet package pythonnet (Python.Runtime.dll) of the same version as the pip one.
// Member names of the ribbon come from DP Technology's public tutorials; the SupportBuild
// number must be ESPRIT's major build.

using System;
using System.ComponentModel.Composition;
using ESPRIT.NetApi.Extensions;
using ESPRIT.NetApi.Ribbon;
using Python.Runtime;

namespace NcperfEsprit
{
    [Export(typeof(IExtension))]
    [ExportMetadata("SupportBuild", 20)]
    public class NcperfExtension : IExtension
    {
        const string TabKey = "ncperf", GroupKey = "ncperf.group", ButtonKey = "ncperf.run";
        Esprit.Application app;
        IRibbon ribbon;

        public string Name => "ncperf performance viewer";
        public string Description => "Predicted feed reduction of the selected operations (Tapie et al.)";
        public string Publisher => "ncperf";
        public string Url => "https://pypi.org/project/ncperf/";

        public void Connect(object application)
        {
            app = (Esprit.Application)application;
            ribbon = (IRibbon)app.Ribbon;
            var tab = ribbon.Tabs.Contains(TabKey) ? ribbon.Tabs.Item(TabKey) : ribbon.Tabs.Add(TabKey, "ncperf");
            tab.Groups.Add(GroupKey, "Performance").Items.AddButton(ButtonKey, "Performance viewer", true, null);
            ribbon.OnButtonClick += OnClick;
        }

        void OnClick(object sender, ButtonClickEventArgs e)
        {
            if (e.Key != ButtonKey) return;
            string text;
            try
            {
                if (!PythonEngine.IsInitialized)
                {
                    // NCPERF_PYTHON_DLL: the python3XX.dll of the Python that has ncperf installed.
                    Runtime.PythonDLL = Environment.GetEnvironmentVariable("NCPERF_PYTHON_DLL") ?? "python311.dll";
                    PythonEngine.Initialize();
                    PythonEngine.BeginAllowThreads();
                }
                using (Py.GIL())
                {
                    dynamic addin = Py.Import("adapters.esprit_com.addin");
                    text = (string)addin.run(app.ToPython());
                }
            }
            catch (PythonException ex)
            {
                text = "ncperf: " + ex.Message;
            }
            app.EventWindow.AddMessage(EspritConstants.espMessageType.espMessageTypeInformation, "ncperf", text);
            app.EventWindow.Visible = true;
        }

        public void Disconnect()
        {
            if (ribbon != null) ribbon.OnButtonClick -= OnClick;
            ribbon = null;
            app = null;
        }
    }
}
