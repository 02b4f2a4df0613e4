// A headless emulation of the part of ESPRIT's object model ncperf uses (issue 3).
//
// Same member names as DP Technology's public add-in tutorials, 1-based collections, the same
// tool path item types; enum values are the assumptions of adapters/esprit_com/object_model.py
// (a test checks they agree). Compiled by scripts/setup_esprit_emulation.sh with Mono's mcs and
// loaded through pythonnet, so the adapter's code runs against a real .NET object model.
//
// The ESPRIT-like classes hold ESPRIT members only. What a real ESPRIT does through its UI --
// making operations and tool paths, selecting -- and what tests need to read back -- what was
// drawn, undo steps -- is in the static class Emulation, which no adapter code calls.

using System;
using System.Collections;
using System.Collections.Generic;

namespace EspritEmulation
{
    public enum espToolPathItemType
    {
        tpiSTART_POINT = 0,
        tpiEND_POINT = 1,
        tpiSEG2 = 2,
        tpiSEG3 = 3,
        tpiARC2 = 4,
        tpiARC3 = 5,
    }

    public enum espGraphicObjectType
    {
        espPoint = 1,
        espSegment = 2,
        espArc = 3,
        espOperation = 40,
    }

    public enum espUnitType
    {
        espInch = 0,
        espMetric = 1,
    }

    // ------------------------------------------------------------------ tool path geometry
    public class ComPoint
    {
        public double X { get; set; }
        public double Y { get; set; }
        public double Z { get; set; }
        public ComPoint(double x, double y, double z) { X = x; Y = y; Z = z; }
        public ComPoint Copy() { return new ComPoint(X, Y, Z); }
    }

    public class ComVector
    {
        public double X { get; set; }
        public double Y { get; set; }
        public double Z { get; set; }
        public ComVector(double x, double y, double z) { X = x; Y = y; Z = z; }
        public ComVector Copy() { return new ComVector(X, Y, Z); }
    }

    public class ComSegment
    {
        public ComPoint StartPoint { get; set; }
        public ComPoint EndPoint { get; set; }
        public double Length
        {
            get
            {
                double dx = EndPoint.X - StartPoint.X, dy = EndPoint.Y - StartPoint.Y,
                       dz = EndPoint.Z - StartPoint.Z;
                return Math.Sqrt(dx * dx + dy * dy + dz * dz);
            }
        }
        public ComSegment Copy()
        {
            return new ComSegment { StartPoint = StartPoint.Copy(), EndPoint = EndPoint.Copy() };
        }
    }

    public class ComArc
    {
        public ComPoint CenterPoint { get; set; }
        public double Radius { get; set; }
        public ComVector U { get; set; }
        public ComVector V { get; set; }
        public double StartAngle { get; set; }
        public double EndAngle { get; set; }
        public double Length
        {
            get
            {
                double sweep = EndAngle - StartAngle;
                if (sweep <= 0) sweep += 2 * Math.PI;
                return Radius * sweep;
            }
        }
        public ComArc Copy()
        {
            return new ComArc
            {
                CenterPoint = CenterPoint.Copy(), Radius = Radius, U = U.Copy(), V = V.Copy(),
                StartAngle = StartAngle, EndAngle = EndAngle,
            };
        }
    }

    public class ToolPathItem
    {
        public espToolPathItemType Type { get; set; }
        public int AuxCode { get; set; }
        // Declared object, as in ESPRIT: callers cast it to IComPoint/IComSegment/IComArc.
        public object data { get; set; }

        internal ToolPathItem Copy()
        {
            object d = data;
            if (d is ComPoint) d = ((ComPoint)d).Copy();
            else if (d is ComSegment) d = ((ComSegment)d).Copy();
            else if (d is ComArc) d = ((ComArc)d).Copy();
            return new ToolPathItem { Type = Type, AuxCode = AuxCode, data = d };
        }
    }

    public class ToolPath
    {
        internal readonly List<ToolPathItem> items = new List<ToolPathItem>();
        public int Count { get { return items.Count; } }

        // 1-based, and a copy: changing it does not change the tool path (as in ESPRIT).
        public ToolPathItem ItemCopy(int i)
        {
            if (i < 1 || i > items.Count)
                throw new ArgumentOutOfRangeException("i", i, "tool path items are numbered 1.." + items.Count);
            return items[i - 1].Copy();
        }
    }

    // A milling technology: ESPRIT has one class per cycle; they share these feed members.
    public class TechMill3DFinish
    {
        public double XYFeedratePM { get; set; }
        public double ZFeedratePM { get; set; }
    }

    public class PartOperation
    {
        public string Name { get; set; }
        public int Key { get; internal set; }
        public ToolPath ToolPath { get; internal set; }
        public object Technology { get; internal set; }
        public double LengthOfFeed { get; internal set; }
        public double LengthOfRapid { get; internal set; }
        public bool Suppress { get; set; }
        public espGraphicObjectType GraphicObjectType { get { return espGraphicObjectType.espOperation; } }
    }

    public class PartOperations : IEnumerable
    {
        internal readonly List<PartOperation> items = new List<PartOperation>();
        public int Count { get { return items.Count; } }
        public PartOperation this[int i]
        {
            get
            {
                if (i < 1 || i > items.Count)
                    throw new ArgumentOutOfRangeException("i", i, "operations are numbered 1.." + items.Count);
                return items[i - 1];
            }
        }
        public IEnumerator GetEnumerator() { return items.GetEnumerator(); }
    }

    // The selection.
    public class Group : IEnumerable
    {
        internal readonly List<object> items = new List<object>();
        public int Count { get { return items.Count; } }
        public object this[int i]
        {
            get
            {
                if (i < 1 || i > items.Count)
                    throw new ArgumentOutOfRangeException("i", i, "the group holds 1.." + items.Count);
                return items[i - 1];
            }
        }
        public IEnumerator GetEnumerator() { return items.GetEnumerator(); }
    }

    // ------------------------------------------------------------------ drawing
    public class Layer
    {
        public string Name { get; internal set; }
        public bool Visible { get; set; }
    }

    public class Layers : IEnumerable
    {
        internal readonly Document doc;
        internal List<Layer> items = new List<Layer>();
        internal Layers(Document d) { doc = d; }
        public int Count { get { return items.Count; } }
        public Layer this[int i]
        {
            get
            {
                if (i < 1 || i > items.Count)
                    throw new ArgumentOutOfRangeException("i", i, "layers are numbered 1.." + items.Count);
                return items[i - 1];
            }
        }
        public Layer Add(string name)
        {
            if (string.IsNullOrEmpty(name)) throw new ArgumentException("a layer needs a name");
            foreach (Layer l in items)
                if (l.Name == name) throw new ArgumentException("layer '" + name + "' exists");
            var layer = new Layer { Name = name, Visible = true };
            items.Add(layer);
            return layer;
        }
        // Removes the layer and what is drawn on it.
        public void Remove(string name)
        {
            Layer found = items.Find(l => l.Name == name);
            if (found == null) throw new ArgumentException("no layer '" + name + "'");
            if (found == doc.activeLayer) throw new InvalidOperationException("cannot remove the active layer");
            items.Remove(found);
            doc.segments.items.RemoveAll(o => o.Layer == found);
            doc.arcs.items.RemoveAll(o => o.Layer == found);
            doc.points.items.RemoveAll(o => o.Layer == found);
        }
        public IEnumerator GetEnumerator() { return items.GetEnumerator(); }
    }

    public class Point
    {
        public double X { get; set; }
        public double Y { get; set; }
        public double Z { get; set; }
        public uint Color { get; set; }
        public Layer Layer { get; set; }
        public espGraphicObjectType GraphicObjectType { get { return espGraphicObjectType.espPoint; } }
    }

    public class Segment
    {
        public Point StartPoint { get; internal set; }
        public Point EndPoint { get; internal set; }
        public uint Color { get; set; }
        public Layer Layer { get; set; }
        public espGraphicObjectType GraphicObjectType { get { return espGraphicObjectType.espSegment; } }
    }

    public class Arc
    {
        public Point CenterPoint { get; internal set; }
        public double Radius { get; internal set; }
        public double StartAngle { get; set; }
        public double EndAngle { get; set; }
        public double Ux { get; set; }
        public double Uy { get; set; }
        public double Uz { get; set; }
        public double Vx { get; set; }
        public double Vy { get; set; }
        public double Vz { get; set; }
        public uint Color { get; set; }
        public Layer Layer { get; set; }
        public espGraphicObjectType GraphicObjectType { get { return espGraphicObjectType.espArc; } }
    }

    public class GraphicList<T> : IEnumerable
    {
        internal readonly Document doc;
        internal List<T> items = new List<T>();
        internal GraphicList(Document d) { doc = d; }
        public int Count { get { return items.Count; } }
        public T this[int i]
        {
            get
            {
                if (i < 1 || i > items.Count)
                    throw new ArgumentOutOfRangeException("i", i, "numbered 1.." + items.Count);
                return items[i - 1];
            }
        }
        public IEnumerator GetEnumerator() { return items.GetEnumerator(); }
        internal static void CheckFinite(double v, string what)
        {
            if (double.IsNaN(v) || double.IsInfinity(v))
                throw new ArgumentException(what + " must be finite, got " + v);
        }
        internal static Point CheckPoint(Point p, string what)
        {
            if (p == null) throw new ArgumentNullException(what);
            return p;
        }
    }

    public class Segments : GraphicList<Segment>
    {
        internal Segments(Document d) : base(d) { }
        public Segment Add(Point p1, Point p2)
        {
            var s = new Segment { StartPoint = CheckPoint(p1, "p1"), EndPoint = CheckPoint(p2, "p2") };
            s.Color = doc.ActiveColor;
            s.Layer = doc.activeLayer;
            items.Add(s);
            return s;
        }
    }

    public class Arcs : GraphicList<Arc>
    {
        internal Arcs(Document d) : base(d) { }
        public Arc Add(Point center, double radius, double startAngle, double endAngle)
        {
            CheckPoint(center, "center");
            CheckFinite(radius, "radius");
            CheckFinite(startAngle, "start angle");
            CheckFinite(endAngle, "end angle");
            if (radius <= 0) throw new ArgumentException("arc radius must be positive, got " + radius);
            var a = new Arc
            {
                CenterPoint = center, Radius = radius, StartAngle = startAngle, EndAngle = endAngle,
                Ux = 1, Uy = 0, Uz = 0, Vx = 0, Vy = 1, Vz = 0,
                Color = doc.ActiveColor, Layer = doc.activeLayer,
            };
            items.Add(a);
            return a;
        }
    }

    public class Points : GraphicList<Point>
    {
        internal Points(Document d) : base(d) { }
        public Point Add(double x, double y, double z)
        {
            CheckFinite(x, "x"); CheckFinite(y, "y"); CheckFinite(z, "z");
            var p = new Point { X = x, Y = y, Z = z, Color = doc.ActiveColor, Layer = doc.activeLayer };
            items.Add(p);
            return p;
        }
    }

    // ------------------------------------------------------------------ document, application
    public class Document
    {
        internal readonly PartOperations operations = new PartOperations();
        internal readonly Group group = new Group();
        internal readonly Layers layers;
        internal readonly Segments segments;
        internal readonly Arcs arcs;
        internal readonly Points points;
        internal Layer activeLayer;
        internal Snapshot transaction;
        internal int undoSteps, cancelled, refreshes;

        public Document(string name)
        {
            Name = name;
            layers = new Layers(this);
            segments = new Segments(this);
            arcs = new Arcs(this);
            points = new Points(this);
            activeLayer = layers.Add("Default");
            SystemUnit = espUnitType.espMetric;
        }

        public string Name { get; set; }
        public espUnitType SystemUnit { get; set; }
        public PartOperations PartOperations { get { return operations; } }
        public Group Group { get { return group; } }
        public Layers Layers { get { return layers; } }
        public Segments Segments { get { return segments; } }
        public Arcs Arcs { get { return arcs; } }
        public Points Points { get { return points; } }
        public uint ActiveColor { get; set; }
        public Layer ActiveLayer
        {
            get { return activeLayer; }
            set
            {
                if (value == null || !layers.items.Contains(value))
                    throw new ArgumentException("the active layer must be a layer of this document");
                activeLayer = value;
            }
        }

        // A point to pass to Segments.Add / Arcs.Add; not itself drawn.
        public Point GetPoint(double x, double y, double z)
        {
            GraphicList<Point>.CheckFinite(x, "x");
            GraphicList<Point>.CheckFinite(y, "y");
            GraphicList<Point>.CheckFinite(z, "z");
            return new Point { X = x, Y = y, Z = z };
        }

        public void OpenUndoTransaction()
        {
            if (transaction != null) throw new InvalidOperationException("an undo transaction is already open");
            transaction = new Snapshot(this);
        }

        // keep: one undo step; otherwise everything since OpenUndoTransaction is cancelled.
        public void CloseUndoTransaction(bool keep)
        {
            if (transaction == null) throw new InvalidOperationException("no undo transaction is open");
            if (keep) undoSteps++;
            else { transaction.Restore(this); cancelled++; }
            transaction = null;
        }

        public void Refresh() { refreshes++; }
    }

    internal class Snapshot
    {
        readonly List<Layer> layers;
        readonly List<Segment> segments;
        readonly List<Arc> arcs;
        readonly List<Point> points;
        readonly Layer active;
        readonly uint colour;
        internal Snapshot(Document d)
        {
            layers = new List<Layer>(d.layers.items);
            segments = new List<Segment>(d.segments.items);
            arcs = new List<Arc>(d.arcs.items);
            points = new List<Point>(d.points.items);
            active = d.activeLayer;
            colour = d.ActiveColor;
        }
        internal void Restore(Document d)
        {
            d.layers.items = layers;
            d.segments.items = segments;
            d.arcs.items = arcs;
            d.points.items = points;
            d.activeLayer = active;
            d.ActiveColor = colour;
        }
    }

    public class Application
    {
        public Application(string documentName) { Document = new Document(documentName); }
        public Document Document { get; private set; }
        public string Name { get { return "ESPRIT (ncperf emulation)"; } }
    }

    // ------------------------------------------------------------------ not ESPRIT
    // Filling documents (what ESPRIT's UI does) and reading back what was drawn (for tests and
    // the SVG rendering). Arrays are flat so that Python passes them with one copy.
    public static class Emulation
    {
        public const int ItemStride = 12;

        public static PartOperation AddOperation(Document doc, string name, double xyFeedratePM,
                                                 double zFeedratePM, bool withToolPath)
        {
            var op = new PartOperation
            {
                Name = name, Key = doc.operations.Count + 1,
                ToolPath = withToolPath ? new ToolPath() : null,
                Technology = new TechMill3DFinish { XYFeedratePM = xyFeedratePM, ZFeedratePM = zFeedratePM },
            };
            doc.operations.items.Add(op);
            return op;
        }

        // Item k: types[k], aux[k] and data[12 k .. 12 k + 11]: a point x y z; a segment
        // x0 y0 z0 x1 y1 z1; an arc cx cy cz radius ux uy uz vx vy vz start end. Items of
        // rapidAux count in LengthOfRapid, the others in LengthOfFeed (as ESPRIT reports them).
        public static void AddItems(PartOperation op, int[] types, int[] aux, double[] data, int rapidAux)
        {
            if (op.ToolPath == null) throw new InvalidOperationException("operation has no tool path");
            if (aux.Length != types.Length || data.Length != ItemStride * types.Length)
                throw new ArgumentException("types, aux and data disagree in length");
            for (int k = 0; k < types.Length; k++)
            {
                int o = ItemStride * k;
                var type = (espToolPathItemType)types[k];
                object d = null;
                double length = 0;
                switch (type)
                {
                    case espToolPathItemType.tpiSTART_POINT:
                    case espToolPathItemType.tpiEND_POINT:
                        d = new ComPoint(data[o], data[o + 1], data[o + 2]);
                        break;
                    case espToolPathItemType.tpiSEG2:
                    case espToolPathItemType.tpiSEG3:
                        var s = new ComSegment
                        {
                            StartPoint = new ComPoint(data[o], data[o + 1], data[o + 2]),
                            EndPoint = new ComPoint(data[o + 3], data[o + 4], data[o + 5]),
                        };
                        length = s.Length;
                        d = s;
                        break;
                    case espToolPathItemType.tpiARC2:
                    case espToolPathItemType.tpiARC3:
                        var a = new ComArc
                        {
                            CenterPoint = new ComPoint(data[o], data[o + 1], data[o + 2]),
                            Radius = data[o + 3],
                            U = new ComVector(data[o + 4], data[o + 5], data[o + 6]),
                            V = new ComVector(data[o + 7], data[o + 8], data[o + 9]),
                            StartAngle = data[o + 10], EndAngle = data[o + 11],
                        };
                        length = a.Length;
                        d = a;
                        break;
                }
                op.ToolPath.items.Add(new ToolPathItem { Type = type, AuxCode = aux[k], data = d });
                if (aux[k] == rapidAux) op.LengthOfRapid += length;
                else op.LengthOfFeed += length;
            }
        }

        public static void SetLengths(PartOperation op, double feed, double rapid)
        {
            op.LengthOfFeed = feed;
            op.LengthOfRapid = rapid;
        }

        public static void Select(Document doc, object obj) { doc.group.items.Add(obj); }

        static int LayerIndex(Document doc, Layer layer) { return doc.layers.items.IndexOf(layer); }

        public static string[] LayerNames(Document doc)
        {
            var names = new string[doc.layers.items.Count];
            for (int i = 0; i < names.Length; i++) names[i] = doc.layers.items[i].Name;
            return names;
        }

        // Per segment: x0 y0 z0 x1 y1 z1 colour layer (layer: 0-based index into LayerNames).
        public static double[] SegmentRecords(Document doc)
        {
            var list = doc.segments.items;
            var r = new double[8 * list.Count];
            for (int i = 0; i < list.Count; i++)
            {
                var s = list[i];
                int o = 8 * i;
                r[o] = s.StartPoint.X; r[o + 1] = s.StartPoint.Y; r[o + 2] = s.StartPoint.Z;
                r[o + 3] = s.EndPoint.X; r[o + 4] = s.EndPoint.Y; r[o + 5] = s.EndPoint.Z;
                r[o + 6] = s.Color; r[o + 7] = LayerIndex(doc, s.Layer);
            }
            return r;
        }

        // Per arc: cx cy cz radius ux uy uz vx vy vz start end colour layer.
        public static double[] ArcRecords(Document doc)
        {
            var list = doc.arcs.items;
            var r = new double[14 * list.Count];
            for (int i = 0; i < list.Count; i++)
            {
                var a = list[i];
                int o = 14 * i;
                r[o] = a.CenterPoint.X; r[o + 1] = a.CenterPoint.Y; r[o + 2] = a.CenterPoint.Z;
                r[o + 3] = a.Radius;
                r[o + 4] = a.Ux; r[o + 5] = a.Uy; r[o + 6] = a.Uz;
                r[o + 7] = a.Vx; r[o + 8] = a.Vy; r[o + 9] = a.Vz;
                r[o + 10] = a.StartAngle; r[o + 11] = a.EndAngle;
                r[o + 12] = a.Color; r[o + 13] = LayerIndex(doc, a.Layer);
            }
            return r;
        }

        // Per point: x y z colour layer.
        public static double[] PointRecords(Document doc)
        {
            var list = doc.points.items;
            var r = new double[5 * list.Count];
            for (int i = 0; i < list.Count; i++)
            {
                var p = list[i];
                int o = 5 * i;
                r[o] = p.X; r[o + 1] = p.Y; r[o + 2] = p.Z;
                r[o + 3] = p.Color; r[o + 4] = LayerIndex(doc, p.Layer);
            }
            return r;
        }

        public static int UndoSteps(Document doc) { return doc.undoSteps; }
        public static int Cancelled(Document doc) { return doc.cancelled; }
        public static int Refreshes(Document doc) { return doc.refreshes; }
        public static bool TransactionOpen(Document doc) { return doc.transaction != null; }

        public static string[] EnumNames(string which)
        {
            return Enum.GetNames(EnumType(which));
        }

        public static int[] EnumValues(string which)
        {
            var values = Enum.GetValues(EnumType(which));
            var r = new int[values.Length];
            for (int i = 0; i < r.Length; i++) r[i] = (int)values.GetValue(i);
            return r;
        }

        static Type EnumType(string which)
        {
            switch (which)
            {
                case "espToolPathItemType": return typeof(espToolPathItemType);
                case "espGraphicObjectType": return typeof(espGraphicObjectType);
                case "espUnitType": return typeof(espUnitType);
            }
            throw new ArgumentException("no enum " + which);
        }
    }
}
